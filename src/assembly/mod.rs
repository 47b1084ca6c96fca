//! Degrees of freedom, the global sparsity pattern (built once) and the parallel assembler.
//!
//! * [`DofMap`]: the *full* unknown vector holds `n_comp` field components per node
//!   (`n_comp·node + i`: 2 displacement components for the solid, 1 for a scalar problem such
//!   as Poisson) followed by optional cell-owned unknowns (e.g. the three discontinuous P1
//!   pressures of a Q2/P1 cell, `n_comp·n_nodes + 3·cell + m`) and global unknowns. Each full dof maps to an equation
//!   number or to [`FIXED`] (Dirichlet: its value lives in the full vector and never changes
//!   during a Newton solve) or to [`CONSTRAINED`]: a hanging node's dof, x_d = Σ w x_m over
//!   unconstrained masters ([`DofMap::expansion`], from [`crate::mesh::Mesh::constraints`]),
//!   kept up to date in the full vector by [`DofMap::scatter_free`] / [`DofMap::add_free`].
//!   Cells carry their own dof lists, so cells of different degree coexist.
//! * [`Assembler`]: CSC pattern of the free equations (both triangles), a per-cell table of
//!   value slots for every local (row, col) pair, and a cell colouring. Assembly zero-fills the
//!   values and scatters cell contributions; a constrained row or column is scattered to its
//!   masters with its weights (Cᵀ K C, Cᵀ r), from per-element tables built once. Parallel schedule, lock-free: the elements are cut
//!   into contiguous chunks such that chunks two apart share no dof (even chunks in parallel,
//!   then odd ones: each thread walks contiguous memory), or, when no such cut exists (tiny or
//!   unstructured meshes), coloured so that elements of one colour share no node. The result is
//!   independent of the thread count up to summation order.
//! * The assembly also accumulates, per equation, the sum of the magnitudes of the element
//!   contributions, [`Assembler::scale`] (q_i = Σ_e |r_e,i|: the "force flux" through equation
//!   i). It is the physical force scale of Newton's convergence test (see
//!   [`crate::solver::newton`]): it is large wherever forces are transmitted, even where they
//!   balance, and it follows the current state (no memory of an earlier, larger residual).

pub mod constraints;
pub mod qp;

use crate::mesh::Mesh;
use rayon::prelude::*;

pub use qp::{QpData, QpHistory};

/// Marker of a fixed (Dirichlet) dof in [`DofMap::eq`].
pub const FIXED: u32 = u32::MAX;
/// Marker of a constrained dof (a hanging node's, [`DofMap::expansion`]) in [`DofMap::eq`].
pub const CONSTRAINED: u32 = u32::MAX - 1;
/// Largest local system: Q2 displacements (18) + P1 pressures (3).
pub const MAX_LOCAL: usize = 21;

/// The cells of a mesh as [`DofMap::for_cells`] numbers them: node count, cell count, each
/// cell's nodes in its local order, and the hanging-node constraints (empty for a conforming
/// mesh).
#[derive(Clone, Copy)]
pub struct CellTopology<'a> {
    pub n_nodes: usize,
    pub n_cells: usize,
    pub cell_nodes: &'a (dyn Fn(usize) -> &'a [u32] + Sync),
    pub constraints: &'a [crate::mesh::NodeConstraint],
}

#[derive(Clone, Debug)]
pub struct DofMap {
    /// Field components per node (2 for the solid's displacements, 1 for a scalar field).
    pub n_comp: usize,
    /// Number of nodal dofs (`n_comp` per node).
    pub n_u: usize,
    /// Cell-owned dofs per cell (0 or 3).
    pub per_cell: usize,
    /// Global unknowns at the end of the full vector.
    pub n_global: usize,
    /// Equation number of each full dof, or [`FIXED`], or [`CONSTRAINED`].
    pub eq: Vec<u32>,
    /// Number of equations (free dofs).
    pub n_eq: usize,
    /// Field of each equation: 0 displacement, 1 pressure, 2 global unknowns.
    pub field: Vec<u8>,
    /// Full-dof list of each cell (CSR): nodal dofs in local node order (`n_comp·a + i`), then
    /// the cell-owned dofs.
    pub cell_dofs: Vec<u32>,
    pub cell_offsets: Vec<usize>,
    /// Constrained dofs (ascending) and their expansions x_d = Σ w x_m over unconstrained
    /// (free or fixed) full dofs m: `cons_terms[cons_offsets[k]..cons_offsets[k + 1]]` for
    /// `cons_dofs[k]`. Empty without hanging nodes.
    pub cons_dofs: Vec<u32>,
    pub cons_offsets: Vec<usize>,
    pub cons_terms: Vec<(u32, f64)>,
}

impl DofMap {
    /// The solid's map: two displacement dofs per node plus `per_cell` dofs per cell;
    /// `fixed_nodes` have both displacement components fixed.
    pub fn new(mesh: &Mesh, per_cell: usize, fixed_nodes: &[u32]) -> Self {
        Self::with_globals(mesh, per_cell, fixed_nodes, 0)
    }

    /// As [`Self::new`] plus `n_global` free global unknowns at the end of the full vector (e.g.
    /// the road height under load control).
    pub fn with_globals(
        mesh: &Mesh,
        per_cell: usize,
        fixed_nodes: &[u32],
        n_global: usize,
    ) -> Self {
        Self::with_components(mesh, 2, per_cell, fixed_nodes, n_global)
    }

    /// `n_comp ≥ 1` field components per node, `per_cell` cell-owned dofs per cell and
    /// `n_global` global unknowns; every component of the `fixed_nodes` is fixed, and every
    /// component of a hanging node follows the same component of its masters
    /// ([`crate::mesh::Mesh::constraints`], stated per node).
    pub fn with_components(
        mesh: &Mesh,
        n_comp: usize,
        per_cell: usize,
        fixed_nodes: &[u32],
        n_global: usize,
    ) -> Self {
        let n_u = n_comp * mesh.n_nodes();
        let mut fixed = vec![false; n_u];
        for &n in fixed_nodes {
            let first = n_comp * n as usize;
            fixed[first..first + n_comp].fill(true);
        }
        Self::for_cells(
            CellTopology {
                n_nodes: mesh.n_nodes(),
                n_cells: mesh.n_cells(),
                cell_nodes: &|c| mesh.cell_nodes(c),
                constraints: &mesh.constraints,
            },
            n_comp,
            per_cell,
            &fixed,
            n_global,
        )
    }

    /// The map of any cell topology (2D or 3D): `n_comp ≥ 1` components per node, `per_cell`
    /// cell-owned dofs per cell and `n_global` global unknowns at the end; `fixed_u[n_comp·n + i]`
    /// fixes component i of node n (shorter than the nodal dofs: the rest is free). Hanging
    /// nodes of `topology.constraints` follow their masters component by component.
    pub fn for_cells(
        topology: CellTopology<'_>,
        n_comp: usize,
        per_cell: usize,
        fixed_u: &[bool],
        n_global: usize,
    ) -> Self {
        let nc = n_comp as u32;
        let n_cells = topology.n_cells;
        let n_u = n_comp * topology.n_nodes;
        let n_full = n_u + per_cell * n_cells + n_global;
        let mut fixed = vec![false; n_full];
        let k = fixed_u.len().min(n_u);
        fixed[..k].copy_from_slice(&fixed_u[..k]);
        // Hanging nodes (a fixed node stays fixed): each component follows its masters'.
        let mut cons_dofs = Vec::new();
        let mut cons_offsets = vec![0];
        let mut cons_terms = Vec::new();
        let mut constrained = vec![false; n_full];
        for c in topology.constraints {
            for i in 0..nc {
                let d = nc * c.node + i;
                if fixed[d as usize] {
                    continue;
                }
                constrained[d as usize] = true;
                cons_dofs.push(d);
                cons_terms.extend(c.masters.iter().map(|&(m, w)| (nc * m + i, w)));
                cons_offsets.push(cons_terms.len());
            }
        }
        let mut eq = vec![FIXED; n_full];
        let mut field = Vec::with_capacity(n_full);
        let mut n_eq = 0u32;
        for (d, e) in eq.iter_mut().enumerate() {
            if constrained[d] {
                *e = CONSTRAINED;
            } else if !fixed[d] {
                *e = n_eq;
                field.push(if d < n_u {
                    0
                } else if d < n_u + per_cell * n_cells {
                    1
                } else {
                    2
                });
                n_eq += 1;
            }
        }
        let mut cell_dofs = Vec::new();
        let mut cell_offsets = vec![0];
        for c in 0..n_cells {
            for &n in (topology.cell_nodes)(c) {
                cell_dofs.extend((0..nc).map(|i| nc * n + i));
            }
            for m in 0..per_cell {
                cell_dofs.push((n_u + per_cell * c + m) as u32);
            }
            cell_offsets.push(cell_dofs.len());
        }
        Self {
            n_comp,
            n_u,
            per_cell,
            n_global,
            eq,
            n_eq: n_eq as usize,
            field,
            cell_dofs,
            cell_offsets,
            cons_dofs,
            cons_offsets,
            cons_terms,
        }
    }

    /// Equation number of full dof `d`, if it is free.
    #[inline]
    pub fn equation(&self, d: usize) -> Option<usize> {
        let e = self.eq[d];
        (e < CONSTRAINED).then_some(e as usize)
    }

    /// Whether the discretisation has constrained (hanging-node) dofs.
    pub fn has_constraints(&self) -> bool {
        !self.cons_dofs.is_empty()
    }

    /// The expansion x_d = Σ w x_m of a constrained dof `d` over unconstrained full dofs.
    pub fn expansion(&self, d: u32) -> Option<&[(u32, f64)]> {
        let k = self.cons_dofs.binary_search(&d).ok()?;
        Some(&self.cons_terms[self.cons_offsets[k]..self.cons_offsets[k + 1]])
    }

    /// Set every constrained entry of the full vector from its masters.
    pub fn apply_constraints(&self, full: &mut [f64]) {
        for (k, &d) in self.cons_dofs.iter().enumerate() {
            full[d as usize] = self.cons_terms[self.cons_offsets[k]..self.cons_offsets[k + 1]]
                .iter()
                .map(|&(m, w)| w * full[m as usize])
                .sum();
        }
    }

    /// The equations and weights an element row/column of full dof `d` adds to: itself, the
    /// free masters of a constrained dof, or nothing (fixed).
    fn targets(&self, d: u32, out: &mut Vec<(u32, f64)>) {
        out.clear();
        match self.eq[d as usize] {
            FIXED => {}
            CONSTRAINED => {
                if let Some(exp) = self.expansion(d) {
                    out.extend(
                        exp.iter()
                            .filter(|&&(m, _)| self.eq[m as usize] < CONSTRAINED)
                            .map(|&(m, w)| (self.eq[m as usize], w)),
                    );
                }
            }
            e => out.push((e, 1.0)),
        }
    }

    /// Full index of component `comp` of node `node`.
    #[inline]
    pub fn node_dof(&self, node: usize, comp: usize) -> usize {
        self.n_comp * node + comp
    }

    /// Full index of global unknown `k`.
    pub fn global(&self, k: usize) -> usize {
        self.eq.len() - self.n_global + k
    }
    pub fn n_full(&self) -> usize {
        self.eq.len()
    }
    #[inline]
    pub fn cell(&self, c: usize) -> &[u32] {
        &self.cell_dofs[self.cell_offsets[c]..self.cell_offsets[c + 1]]
    }
    /// Copy the equation values `x` into the full vector (fixed entries untouched).
    pub fn scatter_free(&self, x: &[f64], full: &mut [f64]) {
        for (d, &e) in self.eq.iter().enumerate() {
            if e < CONSTRAINED {
                full[d] = x[e as usize];
            }
        }
        self.apply_constraints(full);
    }
    /// Add `alpha · dx` (equation values) to the full vector.
    pub fn add_free(&self, alpha: f64, dx: &[f64], full: &mut [f64]) {
        for (d, &e) in self.eq.iter().enumerate() {
            if e < CONSTRAINED {
                full[d] += alpha * dx[e as usize];
            }
        }
        self.apply_constraints(full);
    }
}

/// A local element system with room for the largest element (no heap allocation).
pub struct LocalSystem {
    pub nd: usize,
    /// Row-major `nd × nd` matrix.
    pub k: [f64; MAX_LOCAL * MAX_LOCAL],
    pub r: [f64; MAX_LOCAL],
}

impl LocalSystem {
    pub fn new(nd: usize) -> Self {
        Self {
            nd,
            k: [0.0; MAX_LOCAL * MAX_LOCAL],
            r: [0.0; MAX_LOCAL],
        }
    }
    pub fn clear(&mut self, nd: usize) {
        self.nd = nd;
        self.k[..nd * nd].fill(0.0);
        self.r[..nd].fill(0.0);
    }
}

/// A slice that several threads may write to at provably disjoint indices.
///
/// It never hands out a reference into the slice (a `&mut T` obtained from `&self` would let
/// two threads alias one element without the borrow checker seeing it); it only reads and
/// writes single elements through the raw pointer, so the one obligation left to the caller is
/// the one the assembler proves from its colouring: no index is touched by two threads at once.
pub struct SharedMut<'a, T> {
    ptr: *mut T,
    len: usize,
    _marker: std::marker::PhantomData<&'a mut [T]>,
}
// SAFETY: `SharedMut` is a `&mut [T]` split across threads; sending or sharing it is sound for
// `T: Send` because every access goes through the `unsafe` methods below, whose contract
// forbids concurrent access to one index.
unsafe impl<T: Send> Send for SharedMut<'_, T> {}
unsafe impl<T: Send> Sync for SharedMut<'_, T> {}

impl<'a, T: Copy> SharedMut<'a, T> {
    pub fn new(s: &'a mut [T]) -> Self {
        Self {
            ptr: s.as_mut_ptr(),
            len: s.len(),
            _marker: std::marker::PhantomData,
        }
    }
    /// `s[i] = v`.
    ///
    /// # Safety
    /// `i < len`, and no other thread reads or writes index `i` concurrently.
    #[inline(always)]
    pub unsafe fn set(&self, i: usize, v: T) {
        debug_assert!(i < self.len);
        // SAFETY: in bounds and exclusive at `i` by the caller's contract; `ptr` is valid for
        // the lifetime `'a` of the borrowed slice.
        unsafe { self.ptr.add(i).write(v) }
    }
    /// `s[i] += v`.
    ///
    /// # Safety
    /// As for [`SharedMut::set`].
    #[inline(always)]
    pub unsafe fn add(&self, i: usize, v: T)
    where
        T: std::ops::Add<Output = T>,
    {
        debug_assert!(i < self.len);
        // SAFETY: as in `set`; the read and the write are of the same exclusive element.
        unsafe {
            let p = self.ptr.add(i);
            p.write(p.read() + v);
        }
    }
}

/// A family of elements contributing to the global system (e.g. the cells of the mesh, or the
/// contact facets): each element has its list of full dofs; the block stores its value slots
/// and its colouring.
pub struct Block {
    pub dofs: Vec<u32>,
    pub offsets: Vec<usize>,
    /// Per element, the size of its core ([`Assembler::with_blocks_cored`]); `None`: all of it.
    pub core: Option<Vec<u32>>,
    /// Per element, `nd²` slots (row-major local pairs; only the core's rows in a cored block);
    /// `u32::MAX` where a row or column is fixed.
    slots: Vec<u32>,
    slot_offsets: Vec<usize>,
    /// Elements with constrained dofs (empty without): per element, the matrix entries
    /// (local pair index a·nd + b, slot, weight) and residual entries (local a, equation,
    /// weight) of its constrained rows and columns, expanded over their masters.
    con_k: Vec<(u32, u32, f64)>,
    con_k_offsets: Vec<usize>,
    con_r: Vec<(u32, u32, f64)>,
    con_r_offsets: Vec<usize>,
    /// Element colours (no two elements of one colour share a dof); `None`: assemble serially.
    colors: Option<Vec<Vec<u32>>>,
    /// Contiguous chunks of elements such that chunks two apart share no dof: chunks of even
    /// index run in parallel, then the odd ones. Preferred over colours (cache locality).
    chunks: Option<Vec<(usize, usize)>>,
}

impl Block {
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    #[inline]
    pub fn element(&self, e: usize) -> &[u32] {
        &self.dofs[self.offsets[e]..self.offsets[e + 1]]
    }
    /// Split the elements into `n` contiguous chunks and check that chunks two or more apart
    /// share no dof (true when every chunk is thicker than the element bandwidth, e.g. whole
    /// rings of cells in the ring-ordered annulus).
    fn chunk(dofs: &[u32], offsets: &[usize], n_full: usize) -> Option<Vec<(usize, usize)>> {
        let n = offsets.len().saturating_sub(1);
        if n < 256 {
            return None;
        }
        for n_chunks in [16usize, 8, 4] {
            let bounds: Vec<(usize, usize)> = (0..n_chunks)
                .map(|c| (c * n / n_chunks, (c + 1) * n / n_chunks))
                .collect();
            let mut lo = vec![u32::MAX; n_full];
            let mut hi = vec![0u32; n_full];
            for (c, &(a, b)) in bounds.iter().enumerate() {
                for &d in &dofs[offsets[a]..offsets[b]] {
                    lo[d as usize] = lo[d as usize].min(c as u32);
                    hi[d as usize] = hi[d as usize].max(c as u32);
                }
            }
            if lo
                .iter()
                .zip(&hi)
                .all(|(&l, &h)| l == u32::MAX || h - l <= 1)
            {
                return Some(bounds);
            }
        }
        None
    }

    /// Greedy colouring by shared dofs; `None` if more than 64 colours would be needed
    /// (elements sharing a global dof) or the block is too small to gain from threads.
    fn color(dofs: &[u32], offsets: &[usize], n_full: usize) -> Option<Vec<Vec<u32>>> {
        let n = offsets.len().saturating_sub(1);
        if n < 256 {
            return None;
        }
        let mut masks = vec![0u64; n_full];
        let mut colors: Vec<Vec<u32>> = Vec::new();
        for e in 0..n {
            let el = &dofs[offsets[e]..offsets[e + 1]];
            let used = el.iter().fold(0u64, |m, &d| m | masks[d as usize]);
            if used == u64::MAX {
                return None;
            }
            let c = (!used).trailing_zeros() as usize;
            if colors.len() <= c {
                colors.resize_with(c + 1, Vec::new);
            }
            colors[c].push(e as u32);
            for &d in el {
                masks[d as usize] |= 1 << c;
            }
        }
        Some(colors)
    }
}

/// Counting sort of (key, value) pairs into CSR: the values of key k, in the order `visit`
/// gives them, are `vals[ptr[k]..ptr[k + 1]]`. `visit` is called twice (count, then fill) and
/// must give the same pairs both times; keys are below `n`.
fn bucket<T: Copy + Default>(
    n: usize,
    visit: impl Fn(&mut dyn FnMut(usize, T)),
) -> (Vec<usize>, Vec<T>) {
    let mut ptr = vec![0usize; n + 1];
    visit(&mut |k, _| ptr[k + 1] += 1);
    for i in 0..n {
        ptr[i + 1] += ptr[i];
    }
    let mut fill = ptr[..n].to_vec();
    let mut vals = vec![T::default(); ptr[n]];
    visit(&mut |k, v| {
        vals[fill[k]] = v;
        fill[k] += 1;
    });
    (ptr, vals)
}

/// CSC pattern (`col_ptr`, sorted `row_idx`) of the element blocks `lists` (dof lists and
/// offsets in full-dof numbering), constrained dofs expanded to their free masters. Each
/// column is gathered once from the elements that hold it, deduplicated with a marker, and
/// only its distinct rows sorted.
fn block_pattern(
    dofs: &DofMap,
    lists: &[ElementList],
    cores: &[Option<Vec<u32>>],
) -> (Vec<usize>, Vec<usize>) {
    let n = dofs.n_eq;
    // Every element's free equations, flat, each flagged whether it is a core (row) dof.
    let (mut el_eq, mut el_core, mut el_off) =
        (Vec::<u32>::new(), Vec::<bool>::new(), vec![0usize]);
    let mut tgt = Vec::new();
    for (b, (d, o)) in lists.iter().enumerate() {
        let core = cores.get(b).and_then(Option::as_ref);
        for e in 0..o.len().saturating_sub(1) {
            let k = core.map_or(usize::MAX, |c| c[e] as usize);
            for (a, &di) in d[o[e]..o[e + 1]].iter().enumerate() {
                dofs.targets(di, &mut tgt);
                el_eq.extend(tgt.iter().map(|t| t.0));
                el_core.extend(std::iter::repeat_n(a < k, tgt.len()));
            }
            el_off.push(el_eq.len());
        }
    }
    // Equation → the elements that hold it.
    let (inc_ptr, inc) = bucket(n, |f| {
        for e in 0..el_off.len() - 1 {
            for &q in &el_eq[el_off[e]..el_off[e + 1]] {
                f(q as usize, e as u32);
            }
        }
    });
    let mut mark = vec![u32::MAX; n];
    let mut col_ptr = Vec::with_capacity(n + 1);
    col_ptr.push(0usize);
    let mut row_idx = Vec::new();
    for j in 0..n {
        let start = row_idx.len();
        // A column held by the same elements as the one before (the other component of a
        // node) has the same rows.
        if j > 0 && inc[inc_ptr[j]..inc_ptr[j + 1]] == inc[inc_ptr[j - 1]..inc_ptr[j]] {
            row_idx.extend_from_within(col_ptr[j - 1]..start);
            col_ptr.push(row_idx.len());
            continue;
        }
        for &e in &inc[inc_ptr[j]..inc_ptr[j + 1]] {
            let e = e as usize;
            for p in el_off[e]..el_off[e + 1] {
                let q = el_eq[p];
                if el_core[p] && mark[q as usize] != j as u32 {
                    mark[q as usize] = j as u32;
                    row_idx.push(q as usize);
                }
            }
        }
        row_idx[start..].sort_unstable();
        col_ptr.push(row_idx.len());
    }
    (col_ptr, row_idx)
}

/// Per block, the matrix slots of each element: `nd²`, or the rows of its core times `nd` for
/// a cored block (row-major local pairs, `u32::MAX` where
/// the row or the column is not a free equation) and their offsets, in the pattern
/// (`col_ptr`, `row_idx`) of [`block_pattern`]. One sweep over the columns: the rows of a
/// column are scattered into a position map once, and every element entry in that column
/// reads its slot from it.
fn block_slots(
    dofs: &DofMap,
    lists: &[ElementList],
    cores: &[Option<Vec<u32>>],
    col_ptr: &[usize],
    row_idx: &[usize],
) -> Vec<(Vec<u32>, Vec<usize>)> {
    let n = dofs.n_eq;
    let mut out: Vec<(Vec<u32>, Vec<usize>)> = lists
        .iter()
        .enumerate()
        .map(|(bi, (_, o))| {
            let core = cores.get(bi).and_then(Option::as_ref);
            let mut off = Vec::with_capacity(o.len());
            off.push(0usize);
            for e in 0..o.len().saturating_sub(1) {
                let nd = o[e + 1] - o[e];
                let rows = core.map_or(nd, |c| (c[e] as usize).min(nd));
                off.push(off[e] + rows * nd);
            }
            (vec![u32::MAX; off[off.len() - 1]], off)
        })
        .collect();
    // Free equation j → (block, element, local column b) with eq(b) = j.
    let (ptr, inc) = bucket(n, |f| {
        for (bi, (d, o)) in lists.iter().enumerate() {
            for e in 0..o.len().saturating_sub(1) {
                for (b, &di) in d[o[e]..o[e + 1]].iter().enumerate() {
                    let q = dofs.eq[di as usize];
                    if q < CONSTRAINED {
                        f(q as usize, (bi as u32, e as u32, b as u32));
                    }
                }
            }
        }
    });
    let mut pos = vec![0u32; n];
    for j in 0..n {
        for p in col_ptr[j]..col_ptr[j + 1] {
            pos[row_idx[p]] = p as u32;
        }
        for &(bi, e, b) in &inc[ptr[j]..ptr[j + 1]] {
            let (d, o) = &lists[bi as usize];
            let el = &d[o[e as usize]..o[e as usize + 1]];
            let nd = el.len();
            let (slots, off) = &mut out[bi as usize];
            let base = off[e as usize] + b as usize;
            let k = cores
                .get(bi as usize)
                .and_then(Option::as_ref)
                .map_or(usize::MAX, |c| c[e as usize] as usize);
            for (a, &di) in el.iter().enumerate() {
                let q = dofs.eq[di as usize];
                if q < CONSTRAINED && a < k {
                    slots[base + a * nd] = pos[q as usize];
                }
            }
        }
    }
    out
}

/// The assembler's sums (residual, its force-flux scale, matrix values) as elements add to
/// them, possibly from several threads at disjoint indices.
struct Sums<'a> {
    res: SharedMut<'a, f64>,
    scale: SharedMut<'a, f64>,
    values: SharedMut<'a, f64>,
}

impl<'a> Sums<'a> {
    fn new(res: &'a mut [f64], scale: &'a mut [f64], values: &'a mut [f64]) -> Self {
        Self {
            res: SharedMut::new(res),
            scale: SharedMut::new(scale),
            values: SharedMut::new(values),
        }
    }
}

impl Block {
    /// Add element `e`'s residual `r` (one entry per element dof) and, `with_matrix`, its
    /// row-major matrix `k` (at least the rows of its slots) to `out`: free equations
    /// directly, constrained ones over their masters.
    ///
    /// # Safety
    /// No other thread adds to the equations and matrix slots of element `e` meanwhile.
    #[inline]
    unsafe fn scatter(
        &self,
        e: usize,
        dofs: &DofMap,
        r: &[f64],
        k: &[f64],
        with_matrix: bool,
        out: &Sums<'_>,
    ) {
        // SAFETY (of every add): the indices are element e's equations and slots, exclusive to
        // this call by the caller's contract.
        unsafe {
            for (&d, &ra) in self.element(e).iter().zip(r) {
                let q = dofs.eq[d as usize];
                if q < CONSTRAINED {
                    out.res.add(q as usize, ra);
                    out.scale.add(q as usize, ra.abs());
                }
            }
            if with_matrix {
                let sl = &self.slots[self.slot_offsets[e]..self.slot_offsets[e + 1]];
                for (slot, &kv) in sl.iter().zip(k) {
                    if *slot != u32::MAX {
                        out.values.add(*slot as usize, kv);
                    }
                }
            }
            if !self.con_r_offsets.is_empty() {
                for &(a, q, w) in &self.con_r[self.con_r_offsets[e]..self.con_r_offsets[e + 1]] {
                    out.res.add(q as usize, w * r[a as usize]);
                    out.scale.add(q as usize, (w * r[a as usize]).abs());
                }
                if with_matrix {
                    let ck = &self.con_k[self.con_k_offsets[e]..self.con_k_offsets[e + 1]];
                    for &(ab, slot, w) in ck {
                        if slot != u32::MAX {
                            out.values.add(slot as usize, w * k[ab as usize]);
                        }
                    }
                }
            }
        }
    }
}

/// The elements of `chunks` (ranges that share dofs with their neighbours only), the even
/// chunks in parallel, then the odd ones, each chunk with its own scratch from `init`.
fn by_chunks<S>(
    chunks: &[(usize, usize)],
    init: impl Fn() -> S + Sync,
    work: impl Fn(usize, &mut S) + Sync,
) {
    for phase in 0..2 {
        chunks
            .par_iter()
            .skip(phase)
            .step_by(2)
            .for_each(|&(a, b)| {
                let mut scratch = init();
                for e in a..b {
                    work(e, &mut scratch);
                }
            });
    }
}

/// One block's elements: their dofs (full numbering), one after the other, and the offsets.
pub type ElementList = (Vec<u32>, Vec<usize>);

/// Global sparse pattern (union over all blocks), per-block slot tables and colourings; the
/// value and residual buffers.
pub struct Assembler {
    pub n: usize,
    pub col_ptr: Vec<usize>,
    pub row_idx: Vec<usize>,
    pub blocks: Vec<Block>,
    pub values: Vec<f64>,
    pub residual: Vec<f64>,
    /// Σ_e |r_e,i| per equation (same numbering as `residual`), accumulated with it.
    pub scale: Vec<f64>,
    pub parallel: bool,
    /// Scratch of [`Self::add_block_large`] (element residuals and matrices of one batch).
    large_scratch: Vec<f64>,
}

impl Assembler {
    /// Pattern of the mesh cells only (block 0).
    pub fn new(_mesh: &Mesh, dofs: &DofMap) -> Self {
        Self::with_blocks(
            dofs,
            vec![(dofs.cell_dofs.clone(), dofs.cell_offsets.clone())],
        )
    }

    /// No block and an empty pattern for `n` equations (a placeholder until the blocks are
    /// known).
    pub fn unbuilt(n: usize) -> Self {
        Self {
            n,
            col_ptr: vec![0; n + 1],
            row_idx: Vec::new(),
            blocks: Vec::new(),
            values: Vec::new(),
            residual: vec![0.0; n],
            scale: vec![0.0; n],
            parallel: true,
            large_scratch: Vec::new(),
        }
    }

    /// Pattern of several element blocks, each given as (dof lists, offsets) in full-dof
    /// numbering. Block indices follow the order given.
    pub fn with_blocks(dofs: &DofMap, lists: Vec<ElementList>) -> Self {
        let cores = vec![None; lists.len()];
        Self::with_blocks_cored(dofs, lists, cores)
    }

    /// As [`Self::with_blocks`], with per block optionally the size of each element's core:
    /// `cores[b][e] = k` leaves out of the pattern the pairs of element e of block b whose row
    /// is past its first k dofs (its matrix has nonzeros only in the rows of its core: a
    /// coupling block from a cell's residual to nodes beyond the cell). The kernel fills the
    /// first k rows of its matrix; the others are neither zeroed nor assembled. The pattern
    /// is then not structurally symmetric: the LU analyses A + Aᵀ.
    pub fn with_blocks_cored(
        dofs: &DofMap,
        lists: Vec<ElementList>,
        cores: Vec<Option<Vec<u32>>>,
    ) -> Self {
        let n = dofs.n_eq;
        let (col_ptr, row_idx) = block_pattern(dofs, &lists, &cores);
        let mut all_slots = block_slots(dofs, &lists, &cores, &col_ptr, &row_idx).into_iter();
        let blocks = lists
            .into_iter()
            .zip(cores)
            .map(|((d, o), core)| {
                let slot_of = |ei: u32, ej: u32| -> u32 {
                    let (s, e) = (col_ptr[ej as usize], col_ptr[ej as usize + 1]);
                    row_idx[s..e]
                        .binary_search(&(ei as usize))
                        .map(|p| (s + p) as u32)
                        .unwrap_or(u32::MAX)
                };
                let (slots, slot_offsets) = all_slots.next().unwrap_or_default();
                let constrained = dofs.has_constraints();
                let (mut con_k, mut con_r) = (Vec::new(), Vec::new());
                // Constrained rows and columns, expanded over their masters (none without
                // constraints: empty offsets).
                let (mut con_k_offsets, mut con_r_offsets) = if constrained {
                    (vec![0], vec![0])
                } else {
                    (Vec::new(), Vec::new())
                };
                let (mut ti, mut tj) = (Vec::new(), Vec::new());
                let n_con = if constrained {
                    o.len().saturating_sub(1)
                } else {
                    0
                };
                for e in 0..n_con {
                    let el = &d[o[e]..o[e + 1]];
                    let nd = el.len();
                    // Matrix rows past a core are not assembled.
                    let rows = core.as_ref().map_or(nd, |c| (c[e] as usize).min(nd));
                    for (a, &di) in el.iter().enumerate() {
                        let ei = dofs.eq[di as usize];
                        if ei == CONSTRAINED {
                            dofs.targets(di, &mut ti);
                            con_r.extend(ti.iter().map(|&(q, w)| (a as u32, q, w)));
                        }
                        if a >= rows {
                            continue;
                        }
                        for (b, &dj) in el.iter().enumerate() {
                            let ej = dofs.eq[dj as usize];
                            if ei == CONSTRAINED || ej == CONSTRAINED {
                                dofs.targets(di, &mut ti);
                                dofs.targets(dj, &mut tj);
                                for &(qi, wi) in &ti {
                                    for &(qj, wj) in &tj {
                                        con_k.push(((a * nd + b) as u32, slot_of(qi, qj), wi * wj));
                                    }
                                }
                            }
                        }
                    }
                    con_k_offsets.push(con_k.len());
                    con_r_offsets.push(con_r.len());
                }
                // Elements that share a master must not run concurrently: the schedule is
                // built on the element lists extended by their masters.
                let (sd, so) = if constrained {
                    let mut sd = Vec::with_capacity(d.len());
                    let mut so = vec![0];
                    for e in 0..o.len().saturating_sub(1) {
                        for &di in &d[o[e]..o[e + 1]] {
                            sd.push(di);
                            if let Some(exp) = dofs.expansion(di) {
                                sd.extend(exp.iter().map(|t| t.0));
                            }
                        }
                        so.push(sd.len());
                    }
                    (sd, so)
                } else {
                    (Vec::new(), Vec::new())
                };
                let (sd_ref, so_ref) = if constrained { (&sd, &so) } else { (&d, &o) };
                let chunks = Block::chunk(sd_ref, so_ref, dofs.n_full());
                let colors = if chunks.is_some() {
                    None
                } else {
                    Block::color(sd_ref, so_ref, dofs.n_full())
                };
                Block {
                    dofs: d,
                    offsets: o,
                    core,
                    slots,
                    slot_offsets,
                    con_k,
                    con_k_offsets,
                    con_r,
                    con_r_offsets,
                    colors,
                    chunks,
                }
            })
            .collect();
        let nnz = row_idx.len();
        Self {
            n,
            col_ptr,
            row_idx,
            blocks,
            values: vec![0.0; nnz],
            residual: vec![0.0; n],
            scale: vec![0.0; n],
            parallel: true,
            large_scratch: Vec::new(),
        }
    }

    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }
    /// The blocks' element lists and cores, as [`Self::with_blocks_cored`] takes them (to
    /// rebuild the assembler with a block changed).
    pub fn block_lists(&self) -> (Vec<ElementList>, Vec<Option<Vec<u32>>>) {
        self.blocks
            .iter()
            .map(|b| ((b.dofs.clone(), b.offsets.clone()), b.core.clone()))
            .unzip()
    }
    /// Number of colours of block 0 (the cells); 0 if it is assembled serially.
    pub fn n_colors(&self) -> usize {
        self.blocks
            .first()
            .and_then(|b| b.colors.as_ref())
            .map_or(0, Vec::len)
    }
    /// Number of contiguous chunks of block 0 (0 if coloured or serial).
    pub fn n_chunks(&self) -> usize {
        self.blocks
            .first()
            .and_then(|b| b.chunks.as_ref())
            .map_or(0, Vec::len)
    }

    /// Zero the residual and its scale (and the matrix values).
    pub fn zero(&mut self, with_matrix: bool) {
        self.residual.fill(0.0);
        self.scale.fill(0.0);
        if with_matrix {
            self.values.fill(0.0);
        }
    }

    /// Residual and tangent of the cells (block 0) from scratch: [`Self::zero`] then
    /// [`Self::add_block`] for block 0.
    pub fn assemble<K>(&mut self, dofs: &DofMap, with_matrix: bool, kernel: K)
    where
        K: Fn(usize, &mut LocalSystem) + Sync,
    {
        self.zero(with_matrix);
        self.add_block(0, dofs, with_matrix, kernel);
    }

    /// Add the contributions of block `b`. `kernel(element, local)` fills the local system
    /// (already cleared to the element's size) in the element's dof order.
    pub fn add_block<K>(&mut self, b: usize, dofs: &DofMap, with_matrix: bool, kernel: K)
    where
        K: Fn(usize, &mut LocalSystem) + Sync,
    {
        let Some(block) = self.blocks.get(b) else {
            return;
        };
        let out = Sums::new(&mut self.residual, &mut self.scale, &mut self.values);
        let work = |e: usize, loc: &mut LocalSystem| {
            let nd = block.element(e).len();
            loc.clear(nd);
            kernel(e, loc);
            // SAFETY: elements processed concurrently belong to one colour or to chunks two
            // apart and share no dof, so they touch disjoint equations and disjoint (row, col)
            // slots; serial blocks are processed by one thread.
            unsafe { block.scatter(e, dofs, &loc.r[..nd], &loc.k[..nd * nd], with_matrix, &out) };
        };
        match (&block.chunks, &block.colors, self.parallel) {
            (Some(chunks), _, true) => {
                by_chunks(
                    chunks,
                    || Box::new(LocalSystem::new(0)),
                    |e, loc| work(e, loc),
                );
            }
            (_, Some(colors), true) => {
                for color in colors {
                    color.par_iter().with_min_len(64).for_each_init(
                        || Box::new(LocalSystem::new(0)),
                        |loc, &e| work(e as usize, loc),
                    );
                }
            }
            _ => {
                let mut loc = Box::new(LocalSystem::new(0));
                for e in 0..block.len() {
                    work(e, &mut loc);
                }
            }
        }
    }

    /// As [`Self::add_block`] for a block whose elements may have more than [`MAX_LOCAL`]
    /// dofs: `kernel(element, r, k)` fills the zeroed residual `r` (nd) and row-major matrix
    /// `k` (nd², empty without `with_matrix`) of the element, which is added to the residual,
    /// its force-flux scale and the matrix values. A block split into chunks (or a serial
    /// assembler) is assembled element by element from one element's scratch per chunk, as
    /// [`Self::add_block`] does; otherwise the elements are evaluated in parallel batches
    /// into a scratch buffer kept by the assembler (allocated on the first call only) and
    /// scattered serially.
    pub fn add_block_large<K>(&mut self, b: usize, dofs: &DofMap, with_matrix: bool, kernel: K)
    where
        K: Fn(usize, &mut [f64], &mut [f64]) + Sync,
    {
        const BATCH: usize = 256;
        let Some(block) = self.blocks.get(b) else {
            return;
        };
        let n_el = block.len();
        let max_nd = (0..n_el).map(|e| block.element(e).len()).max().unwrap_or(0);
        let stride = max_nd + if with_matrix { max_nd * max_nd } else { 0 };
        // One element into `s` (its residual, then its matrix from `max_nd` on).
        let eval = |e: usize, s: &mut [f64]| {
            let nd = block.element(e).len();
            let (r, k) = s.split_at_mut(max_nd);
            let r = &mut r[..nd];
            let k = &mut k[..if with_matrix { nd * nd } else { 0 }];
            r.fill(0.0);
            // Rows past an element's core are neither zeroed nor assembled (not in the
            // pattern).
            let kc = block.core.as_ref().map_or(nd, |c| (c[e] as usize).min(nd));
            if with_matrix {
                k[..kc * nd].fill(0.0);
            }
            kernel(e, r, k);
        };
        if block.chunks.is_some() || !self.parallel {
            let out = Sums::new(&mut self.residual, &mut self.scale, &mut self.values);
            let work = |e: usize, s: &mut Vec<f64>| {
                eval(e, s);
                let nd = block.element(e).len();
                // SAFETY: chunks assembled concurrently are two apart and share no dof (they
                // touch disjoint equations and slots); a serial assembler runs one element at
                // a time.
                unsafe { block.scatter(e, dofs, &s[..nd], &s[max_nd..], with_matrix, &out) };
            };
            match (&block.chunks, self.parallel) {
                (Some(chunks), true) => by_chunks(chunks, || vec![0.0; stride], work),
                _ => {
                    let mut s = vec![0.0; stride];
                    for e in 0..n_el {
                        work(e, &mut s);
                    }
                }
            }
            return;
        }
        let mut buf = std::mem::take(&mut self.large_scratch);
        if buf.len() < BATCH * stride {
            buf.resize(BATCH * stride, 0.0);
        }
        let mut start = 0;
        while start < n_el {
            let end = (start + BATCH).min(n_el);
            let batch = &mut buf[..(end - start) * stride];
            batch
                .par_chunks_mut(stride)
                .enumerate()
                .for_each(|(i, s)| eval(start + i, s));
            let out = Sums::new(&mut self.residual, &mut self.scale, &mut self.values);
            for (e, s) in (start..end).zip(batch.chunks(stride)) {
                let nd = block.element(e).len();
                // SAFETY: one element at a time, on this thread.
                unsafe { block.scatter(e, dofs, &s[..nd], &s[max_nd..], with_matrix, &out) };
            }
            start = end;
        }
        self.large_scratch = buf;
    }

    /// y = A x with the assembled values (used by checks and tests).
    pub fn matvec(&self, x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        for (j, &xj) in x.iter().enumerate().take(self.n) {
            let col = self.col_ptr[j]..self.col_ptr[j + 1];
            for (&i, &v) in self.row_idx[col.clone()].iter().zip(&self.values[col]) {
                y[i] += v * xj;
            }
        }
    }

    /// Dense copy of the assembled matrix (tiny meshes only: tests and FD checks).
    pub fn to_dense(&self) -> Vec<Vec<f64>> {
        let mut a = vec![vec![0.0; self.n]; self.n];
        for (j, w) in self.col_ptr.windows(2).enumerate().take(self.n) {
            let col = w[0]..w[1];
            for (&i, &v) in self.row_idx[col.clone()].iter().zip(&self.values[col]) {
                a[i][j] += v;
            }
        }
        a
    }
}

#[cfg(test)]
mod cored_block_tests {
    use super::*;
    use crate::mesh::annulus::{annulus, AnnulusSpec};

    /// A block whose elements have a core: its pattern holds the pairs with the row in the
    /// core and no other, it keeps slots for the core's rows only, and the whole pattern is
    /// the union with the cells' pattern.
    #[test]
    fn a_cored_block_leaves_out_the_pairs_outside_its_core() {
        let mesh = annulus(&AnnulusSpec {
            ri: 1.0,
            ro: 2.0,
            n_r: 1,
            n_theta: 8,
            degree: 1,
            grading_r: 1.0,
            grading_theta: 1.0,
        });
        let dofs = DofMap::new(&mesh, 0, &[]);
        // One element: the dofs of nodes 0 and 1 (core), then those of nodes 5 and 6.
        let el: Vec<u32> = [0u32, 1, 5, 6]
            .iter()
            .flat_map(|&n| [2 * n, 2 * n + 1])
            .collect();
        let core = 4usize;
        let lists = vec![(el.clone(), vec![0, el.len()])];
        let cored =
            Assembler::with_blocks_cored(&dofs, lists.clone(), vec![Some(vec![core as u32])]);
        let full = Assembler::with_blocks(&dofs, lists);
        let has = |asm: &Assembler, i: usize, j: usize| {
            asm.row_idx[asm.col_ptr[j]..asm.col_ptr[j + 1]].contains(&i)
        };
        let nd = el.len();
        let mut left_out = 0;
        for a in 0..nd {
            for b in 0..nd {
                let (i, j) = (
                    dofs.eq[el[a] as usize] as usize,
                    dofs.eq[el[b] as usize] as usize,
                );
                let kept = a < core;
                assert_eq!(has(&cored, i, j), kept, "pair ({a}, {b})");
                assert!(has(&full, i, j), "pair ({a}, {b}) of the full block");
                if kept {
                    let slot = cored.blocks[0].slots[a * nd + b];
                    assert_ne!(slot, u32::MAX, "slot of pair ({a}, {b})");
                    assert_eq!(cored.row_idx[slot as usize], i);
                }
                left_out += usize::from(!kept);
            }
        }
        assert_eq!(left_out, 32);
        // Slots for the core's rows only.
        assert_eq!(cored.blocks[0].slots.len(), core * nd);
        assert_eq!(cored.nnz(), full.nnz() - left_out);
        // Rebuilt from its own lists, the assembler keeps the core.
        let (lists, cores) = cored.block_lists();
        let again = Assembler::with_blocks_cored(&dofs, lists, cores);
        assert_eq!(
            (again.col_ptr.clone(), again.row_idx.clone()),
            (cored.col_ptr.clone(), cored.row_idx.clone())
        );
        // Union with the cells' block: a left-out pair that two cell-mates share stays.
        let cells = (dofs.cell_dofs.clone(), dofs.cell_offsets.clone());
        let both = Assembler::with_blocks_cored(
            &dofs,
            vec![cells, (el.clone(), vec![0, el.len()])],
            vec![None, Some(vec![core as u32])],
        );
        let (i, j) = (
            dofs.eq[el[4] as usize] as usize,
            dofs.eq[el[6] as usize] as usize,
        );
        assert!(has(&both, i, j), "nodes 5 and 6 share a cell");
    }

    /// The pattern is the set of element pairs (core rows × all columns, free dofs only), the
    /// columns shared by one node's two components among them: random element blocks on an
    /// annulus with fixed nodes, elements with one component of a node only (whose columns
    /// then differ from the other component's), and a cored block.
    #[test]
    fn pattern_is_the_set_of_element_pairs() {
        let mesh = annulus(&AnnulusSpec {
            ri: 1.0,
            ro: 2.0,
            n_r: 3,
            n_theta: 12,
            degree: 2,
            grading_r: 1.0,
            grading_theta: 0.0,
        });
        let fixed: Vec<u32> = mesh.node_set("hub").to_vec();
        let dofs = DofMap::new(&mesh, 0, &fixed);
        let n_nodes = mesh.n_nodes() as u64;
        let mut seed = 11u64;
        let mut rnd = move |n: u64| {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 33) % n
        };
        let mut lists = vec![(dofs.cell_dofs.clone(), dofs.cell_offsets.clone())];
        let mut cores = vec![None];
        for cored in [false, true] {
            let (mut d, mut o, mut core) = (Vec::new(), vec![0], Vec::new());
            for _ in 0..40 {
                let start = d.len();
                for _ in 0..1 + rnd(6) {
                    let node = rnd(n_nodes) as u32;
                    match rnd(4) {
                        0 => d.push(2 * node),
                        1 => d.push(2 * node + 1),
                        _ => d.extend([2 * node, 2 * node + 1]),
                    }
                }
                o.push(d.len());
                core.push(rnd((d.len() - start) as u64 + 1) as u32);
            }
            lists.push((d, o));
            cores.push(cored.then_some(core));
        }
        let asm = Assembler::with_blocks_cored(&dofs, lists.clone(), cores.clone());
        let mut want = std::collections::BTreeSet::new();
        for ((d, o), core) in lists.iter().zip(&cores) {
            for e in 0..o.len() - 1 {
                let el = &d[o[e]..o[e + 1]];
                let k = core.as_ref().map_or(el.len(), |c| c[e] as usize);
                for &di in &el[..k] {
                    for &dj in el {
                        let (i, j) = (dofs.eq[di as usize], dofs.eq[dj as usize]);
                        if i < CONSTRAINED && j < CONSTRAINED {
                            want.insert((j as usize, i as usize));
                        }
                    }
                }
            }
        }
        let got: std::collections::BTreeSet<(usize, usize)> = (0..asm.n)
            .flat_map(|j| {
                asm.row_idx[asm.col_ptr[j]..asm.col_ptr[j + 1]]
                    .iter()
                    .map(move |&i| (j, i))
            })
            .collect();
        assert_eq!(got.len(), asm.nnz(), "no duplicate rows in a column");
        assert_eq!(got, want);
        for j in 0..asm.n {
            assert!(asm.row_idx[asm.col_ptr[j]..asm.col_ptr[j + 1]].is_sorted());
        }
    }

    /// `add_block_large` gives the same residual, scale and matrix whichever way it runs: by
    /// chunks (parallel, a block of ≥ 256 elements on rings), by batches (parallel, the
    /// block's chunks taken away) and serially, on a cored block of extended elements (each
    /// cell's dofs, then those of the nodes one passage beyond it along the rings).
    #[test]
    fn large_blocks_assemble_alike_by_chunks_batches_and_serially() {
        let mesh = annulus(&AnnulusSpec {
            ri: 1.0,
            ro: 2.0,
            n_r: 4,
            n_theta: 96,
            degree: 1,
            grading_r: 1.0,
            grading_theta: 1.0,
        });
        let dofs = DofMap::new(&mesh, 0, &[]);
        let per = 96u32;
        let (mut list, mut off, mut core) = (Vec::new(), vec![0], Vec::new());
        for c in 0..mesh.n_cells() {
            let nodes = mesh.cell_nodes(c);
            let mut ex: Vec<u32> = nodes.to_vec();
            for &a in nodes {
                let (ring, pos) = (a / per, a % per);
                for b in [
                    ring * per + (pos + 1) % per,
                    ring * per + (pos + per - 1) % per,
                ] {
                    if !ex.contains(&b) {
                        ex.push(b);
                    }
                }
            }
            core.push(2 * nodes.len() as u32);
            list.extend(ex.iter().flat_map(|&n| [2 * n, 2 * n + 1]));
            off.push(list.len());
        }
        assert!(mesh.n_cells() >= 256);
        let make = || {
            Assembler::with_blocks_cored(
                &dofs,
                vec![(list.clone(), off.clone())],
                vec![Some(core.clone())],
            )
        };
        // A kernel with distinct values per element, row and column.
        let kernel = |e: usize, r: &mut [f64], k: &mut [f64]| {
            let nd = r.len();
            for (a, ra) in r.iter_mut().enumerate() {
                *ra = ((e * 7 + a) % 13) as f64 - 6.0;
            }
            for row in 0..core[e] as usize {
                for col in 0..nd {
                    k[row * nd + col] = ((e * 31 + row * 5 + col * 3) % 17) as f64 * 0.25;
                }
            }
        };
        let run = |asm: &mut Assembler| {
            asm.zero(true);
            asm.add_block_large(0, &dofs, true, kernel);
            (asm.residual.clone(), asm.scale.clone(), asm.values.clone())
        };
        let mut chunked = make();
        assert!(
            chunked.blocks[0].chunks.is_some(),
            "the ring block is chunked"
        );
        let by_chunks = run(&mut chunked);
        let mut batched = make();
        batched.blocks[0].chunks = None;
        let by_batches = run(&mut batched);
        let mut serial = make();
        serial.parallel = false;
        let serially = run(&mut serial);
        // Small integers and quarters: every order of the sums is exact.
        assert_eq!(by_chunks, serially);
        assert_eq!(by_batches, serially);
        assert!(serially.2.iter().any(|&v| v != 0.0));
    }
}
