//! A continuous finite-element space on the leaves of a [`Quadtree`]: per-cell degree,
//! Lagrange (Q1, Q2) or hierarchical (degree 1..=8) tensor-product bases, `n_comp` components
//! per node, and the constraints that make it conforming.
//!
//! *Nodes* are the scalar basis entities: a vertex, an edge mode (edge, k), or an interior mode
//! of a cell; a cell's local function (i, j) (1D entity indices, see
//! [`crate::element::hierarchical`]) is node `cell_nodes[i + (p + 1) j]`. Dof `n_comp·node +
//! comp` carries component `comp` of node `node`.
//!
//! Constraints (x_i = Σ c_ij x_j, stated per node and copied to every component):
//! * **Hanging edges**: the side of a leaf K that is half of a side of a coarser leaf N. The
//!   trace of K on that half must be the restriction of N's trace: K's hanging vertex (the
//!   midpoint of N's side) and K's edge modes are fixed by collocation, Σ_m a_m b_m(t) =
//!   B_g(s(t)) at p_K + 1 Gauss points, for each of N's trace functions B_g (its two vertices
//!   and its edge modes), with s = (t ∓ 1)/2 the coarse edge coordinate of the half.
//! * **Degree transitions** (minimum rule): an edge carries modes up to the smallest degree of
//!   the cells sharing it (for a hanging edge: the coarse cell and both fine cells); the higher
//!   modes of the other cells are constrained to zero.
//! * **Dirichlet data** g on the whole boundary: vertices take g(x); the edge modes of a
//!   boundary edge are the H¹-seminorm projection of g − (vertex part) on the edge.

use super::quadtree::{size_of_level, Across, FxMap, Quadtree, SIDES};
use crate::assembly::constraints::{
    ClosedConstraints, CondensedPattern, ConstraintError, Constraints,
};
use crate::element::hierarchical::{gauss_legendre, Basis1d};
use nalgebra::{DMatrix, DVector};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Key {
    Vertex(i64, i64),
    /// Edge midpoint, direction (0 along x, 1 along y), mode.
    Edge(i64, i64, u8, u8),
    Interior(u32, u8, u8),
}

/// Integer geometry of side `side` of cell (ix, iy, size s): (start point, direction,
/// midpoint).
fn side_geom(ix: i64, iy: i64, s: i64, side: usize) -> ((i64, i64), u8, (i64, i64)) {
    match side {
        0 => ((ix, iy), 1, (ix, iy + s / 2)),
        1 => ((ix + s, iy), 1, (ix + s, iy + s / 2)),
        2 => ((ix, iy), 0, (ix + s / 2, iy)),
        _ => ((ix, iy + s), 0, (ix + s / 2, iy + s)),
    }
}

/// Local index of the 1D-entity pair (i, j) for degree p.
#[inline]
pub fn local_index(p: usize, i: usize, j: usize) -> usize {
    i + (p + 1) * j
}

/// Local indices of the trace functions on `side` in edge order (start vertex, end vertex,
/// modes 2..=p).
fn side_locals(p: usize, side: usize) -> Vec<usize> {
    (0..=p)
        .map(|m| match side {
            0 => local_index(p, 0, m),
            1 => local_index(p, 1, m),
            2 => local_index(p, m, 0),
            _ => local_index(p, m, 1),
        })
        .collect()
}

/// The space: leaves, local-to-node maps, constraints and the condensed pattern.
#[derive(Clone, Debug)]
pub struct Space {
    pub basis: Basis1d,
    pub n_comp: usize,
    /// Leaf cell ids of the tree, in assembly order.
    pub leaves: Vec<u32>,
    /// Degree of each leaf.
    pub degree: Vec<usize>,
    /// Nodes of each leaf (CSR by `node_off`).
    pub cell_nodes: Vec<u32>,
    pub node_off: Vec<usize>,
    pub n_nodes: usize,
    /// Dofs of each leaf (n_comp per node, node-major), CSR by `dof_off`.
    pub cell_dofs: Vec<u32>,
    pub dof_off: Vec<usize>,
    pub constraints: ClosedConstraints,
    pub pattern: CondensedPattern,
    /// Index in `leaves` of a tree cell.
    pub leaf_index: FxMap<u32, usize>,
    /// Number of hanging-edge constraints stated (diagnostics).
    pub n_hanging: usize,
}

/// Error while building a space.
#[derive(Debug, thiserror::Error)]
pub enum SpaceError {
    #[error("basis {basis:?} supports degrees 1..={max}, a cell has degree {p}")]
    Degree {
        basis: Basis1d,
        max: usize,
        p: usize,
    },
    #[error("Lagrange cells must all have the same degree (found {0} and {1})")]
    MixedLagrange(usize, usize),
    #[error(transparent)]
    Constraint(#[from] ConstraintError),
    #[error("linear solve failed: {0}")]
    Solve(String),
}

impl Space {
    /// Build the space on the leaves of `tree` (degrees from the cells), with Dirichlet data
    /// `g(x, comp)` on the whole boundary, or none (`None`: every boundary dof free).
    pub fn new(
        tree: &Quadtree,
        basis: Basis1d,
        n_comp: usize,
        g: Option<&dyn Fn([f64; 2], usize) -> f64>,
    ) -> Result<Self, SpaceError> {
        let leaves = tree.leaves();
        let degree: Vec<usize> = leaves
            .iter()
            .map(|&c| tree.cells[c as usize].degree as usize)
            .collect();
        for &p in &degree {
            if p < 1 || p > basis.max_degree() {
                return Err(SpaceError::Degree {
                    basis,
                    max: basis.max_degree(),
                    p,
                });
            }
            if basis == Basis1d::Lagrange && p != degree[0] {
                return Err(SpaceError::MixedLagrange(degree[0], p));
            }
        }
        let leaf_index: FxMap<u32, usize> =
            leaves.iter().enumerate().map(|(k, &c)| (c, k)).collect();
        // 1. Nodes.
        let mut ids: FxMap<Key, u32> = FxMap::default();
        let mut keys: Vec<Key> = Vec::new();
        let mut cell_nodes = Vec::new();
        let mut node_off = vec![0];
        for (k, &c) in leaves.iter().enumerate() {
            let cell = &tree.cells[c as usize];
            let p = degree[k];
            let s = size_of_level(cell.level);
            for j in 0..=p {
                for i in 0..=p {
                    let key = match (i < 2, j < 2) {
                        (true, true) => Key::Vertex(cell.ix + i as i64 * s, cell.iy + j as i64 * s),
                        (true, false) => {
                            Key::Edge(cell.ix + i as i64 * s, cell.iy + s / 2, 1, j as u8)
                        }
                        (false, true) => {
                            Key::Edge(cell.ix + s / 2, cell.iy + j as i64 * s, 0, i as u8)
                        }
                        (false, false) => Key::Interior(c, i as u8, j as u8),
                    };
                    let id = *ids.entry(key).or_insert_with(|| {
                        keys.push(key);
                        (keys.len() - 1) as u32
                    });
                    cell_nodes.push(id);
                }
            }
            node_off.push(cell_nodes.len());
        }
        let n_nodes = keys.len();
        // 2. Edge degrees (minimum rule).
        let mut edge_deg: FxMap<(i64, i64, u8), usize> = FxMap::default();
        let mut hanging: Vec<(usize, usize, u32)> = Vec::new();
        for (k, &c) in leaves.iter().enumerate() {
            let cell = &tree.cells[c as usize];
            let s = size_of_level(cell.level);
            for side in SIDES {
                let (_, dir, mid) = side_geom(cell.ix, cell.iy, s, side);
                let e = edge_deg.entry((mid.0, mid.1, dir)).or_insert(usize::MAX);
                *e = (*e).min(degree[k]);
                if let Across::Coarser(n) = tree.across(c, side) {
                    hanging.push((k, side, n));
                }
            }
        }
        for &(k, side, n) in &hanging {
            let nc = &tree.cells[n as usize];
            let ns = size_of_level(nc.level);
            let (_, dir, mid) = side_geom(nc.ix, nc.iy, ns, side ^ 1);
            let e = edge_deg.entry((mid.0, mid.1, dir)).or_insert(usize::MAX);
            *e = (*e).min(degree[k]);
        }
        // 3. Node constraints.
        let mut nodecons = Constraints::new(n_nodes);
        for (id, key) in keys.iter().enumerate() {
            if let Key::Edge(x, y, dir, m) = *key {
                if let Some(&pe) = edge_deg.get(&(x, y, dir)) {
                    if m as usize > pe {
                        nodecons.constrain(id, Vec::new());
                    }
                }
            }
        }
        let mut n_hanging = 0;
        for &(k, side, n) in &hanging {
            let c = leaves[k];
            let cell = &tree.cells[c as usize];
            let s = size_of_level(cell.level);
            let pk = degree[k];
            let nk = leaf_index[&n];
            let nc = &tree.cells[n as usize];
            let ns = size_of_level(nc.level);
            let (nstart, dir, nmid) = side_geom(nc.ix, nc.iy, ns, side ^ 1);
            let pe = edge_deg[&(nmid.0, nmid.1, dir)];
            let (fstart, _, _) = side_geom(cell.ix, cell.iy, s, side);
            let lower = fstart == nstart;
            // Coarse trace nodes: start vertex, end vertex, modes 2..=pe (from N's local list).
            let nlocal = side_locals(degree[nk], side ^ 1);
            let nnodes = &cell_nodes[node_off[nk]..node_off[nk + 1]];
            let masters: Vec<u32> = (0..=pe).map(|m| nnodes[nlocal[m]]).collect();
            // Collocation on the fine half.
            let (t, _) = gauss_legendre(pk + 1);
            let mut v = DMatrix::<f64>::zeros(pk + 1, pk + 1);
            let mut rhs = DMatrix::<f64>::zeros(pk + 1, pe + 1);
            for (i, &ti) in t.iter().enumerate() {
                let (bf, _, _) = basis.eval(pk, ti);
                for m in 0..=pk {
                    v[(i, m)] = bf[m];
                }
                let sc = if lower {
                    0.5 * (ti - 1.0)
                } else {
                    0.5 * (ti + 1.0)
                };
                let (bc, _, _) = basis.eval(degree[nk], sc);
                for g in 0..=pe {
                    rhs[(i, g)] = bc[g];
                }
            }
            let a = v
                .lu()
                .solve(&rhs)
                .unwrap_or_else(|| DMatrix::zeros(pk + 1, pe + 1));
            let flocal = side_locals(pk, side);
            let fnodes = &cell_nodes[node_off[k]..node_off[k + 1]];
            let hanging_vertex = if lower { 1 } else { 0 };
            for m in std::iter::once(hanging_vertex).chain(2..=pk) {
                let node = fnodes[flocal[m]] as usize;
                let terms: Vec<(u32, f64)> = (0..=pe)
                    .filter(|&g| a[(m, g)].abs() > 1e-13)
                    .map(|g| (masters[g], a[(m, g)]))
                    .collect();
                nodecons.constrain(node, terms);
            }
            n_hanging += 1;
        }
        // 4. Dofs, Dirichlet data.
        let mut cons = Constraints::new(n_nodes * n_comp);
        for (node, kind) in nodecons.kind.iter().enumerate() {
            if let crate::assembly::constraints::DofKind::Linear(t) = kind {
                for comp in 0..n_comp {
                    let terms = t
                        .iter()
                        .map(|&(j, c)| ((n_comp as u32) * j + comp as u32, c))
                        .collect();
                    cons.constrain(n_comp * node + comp, terms);
                }
            }
        }
        let to_x = |i: i64, j: i64| [tree.to_x(i, 0), tree.to_x(j, 1)];
        let (gq, gw) = gauss_legendre(12);
        for (k, &c) in leaves.iter().enumerate() {
            let Some(g) = g else { break };
            let cell = &tree.cells[c as usize];
            let s = size_of_level(cell.level);
            let p = degree[k];
            let nodes = &cell_nodes[node_off[k]..node_off[k + 1]];
            for side in SIDES {
                if tree.across(c, side) != Across::Boundary {
                    continue;
                }
                let (start, dir, _) = side_geom(cell.ix, cell.iy, s, side);
                let end = if dir == 0 {
                    (start.0 + s, start.1)
                } else {
                    (start.0, start.1 + s)
                };
                let (xa, xb) = (to_x(start.0, start.1), to_x(end.0, end.1));
                let local = side_locals(p, side);
                for comp in 0..n_comp {
                    let (ga, gb) = (g(xa, comp), g(xb, comp));
                    cons.fix(n_comp * nodes[local[0]] as usize + comp, ga);
                    cons.fix(n_comp * nodes[local[1]] as usize + comp, gb);
                    if p < 2 {
                        continue;
                    }
                    let nm = p - 1;
                    let mut mm = DMatrix::<f64>::zeros(nm, nm);
                    let mut r = DVector::<f64>::zeros(nm);
                    for (&t, &w) in gq.iter().zip(&gw) {
                        let (b, db, d2b) = basis.eval(p, t);
                        let x = [
                            0.5 * (1.0 - t) * xa[0] + 0.5 * (1.0 + t) * xb[0],
                            0.5 * (1.0 - t) * xa[1] + 0.5 * (1.0 + t) * xb[1],
                        ];
                        let wv = g(x, comp) - ga * b[0] - gb * b[1];
                        for a in 0..nm {
                            r[a] -= w * wv * d2b[a + 2];
                            for bb in 0..nm {
                                mm[(a, bb)] += w * db[a + 2] * db[bb + 2];
                            }
                        }
                    }
                    let cvec = mm.lu().solve(&r).unwrap_or_else(|| DVector::zeros(nm));
                    for a in 0..nm {
                        cons.fix(n_comp * nodes[local[a + 2]] as usize + comp, cvec[a]);
                    }
                }
            }
        }
        let constraints = cons.close()?;
        let mut cell_dofs = Vec::with_capacity(cell_nodes.len() * n_comp);
        let mut dof_off = vec![0];
        for k in 0..leaves.len() {
            for &nd in &cell_nodes[node_off[k]..node_off[k + 1]] {
                for comp in 0..n_comp {
                    cell_dofs.push(n_comp as u32 * nd + comp as u32);
                }
            }
            dof_off.push(cell_dofs.len());
        }
        let pattern = CondensedPattern::new(&constraints, &cell_dofs, &dof_off);
        Ok(Self {
            basis,
            n_comp,
            leaves,
            degree,
            cell_nodes,
            node_off,
            n_nodes,
            cell_dofs,
            dof_off,
            constraints,
            pattern,
            leaf_index,
            n_hanging,
        })
    }

    /// Number of free equations.
    pub fn n_eq(&self) -> usize {
        self.constraints.n_eq
    }
    pub fn n_dofs(&self) -> usize {
        self.n_nodes * self.n_comp
    }
    #[inline]
    pub fn dofs(&self, k: usize) -> &[u32] {
        &self.cell_dofs[self.dof_off[k]..self.dof_off[k + 1]]
    }

    /// Values and physical gradients of the local basis of leaf `k` at reference (ξ, η), for a
    /// cell of side `h`. Returns the number of functions.
    #[inline]
    pub fn shape(
        &self,
        k: usize,
        h: f64,
        xi: f64,
        eta: f64,
        n: &mut [f64],
        dn: &mut [[f64; 2]],
    ) -> usize {
        shape_values(self.basis, self.degree[k], h, xi, eta, n, dn)
    }

    /// Scalar field value and gradient of component `comp` of the dof vector `x` in leaf `k`.
    pub fn eval(
        &self,
        tree: &Quadtree,
        x: &[f64],
        k: usize,
        comp: usize,
        xi: f64,
        eta: f64,
    ) -> (f64, [f64; 2]) {
        let mut n = [0.0; MAX_LOCAL_SCALAR];
        let mut dn = [[0.0; 2]; MAX_LOCAL_SCALAR];
        let h = tree.h(self.leaves[k]);
        let nl = self.shape(k, h, xi, eta, &mut n, &mut dn);
        let dofs = self.dofs(k);
        let (mut v, mut g) = (0.0, [0.0; 2]);
        for a in 0..nl {
            let xa = x[dofs[self.n_comp * a + comp] as usize];
            v += n[a] * xa;
            g[0] += dn[a][0] * xa;
            g[1] += dn[a][1] * xa;
        }
        (v, g)
    }
}

/// Largest number of scalar functions of one cell (degree 10).
pub const MAX_LOCAL_SCALAR: usize = 121;

/// Values and physical gradients of the tensor basis of degree p at (ξ, η) on a square of side
/// h (∂x = (2/h) ∂ξ).
#[inline]
pub fn shape_values(
    basis: Basis1d,
    p: usize,
    h: f64,
    xi: f64,
    eta: f64,
    n: &mut [f64],
    dn: &mut [[f64; 2]],
) -> usize {
    let (bx, dbx, _) = basis.eval(p, xi);
    let (by, dby, _) = basis.eval(p, eta);
    let sc = 2.0 / h;
    let m = p + 1;
    for j in 0..m {
        for i in 0..m {
            let a = i + m * j;
            n[a] = bx[i] * by[j];
            dn[a] = [sc * dbx[i] * by[j], sc * bx[i] * dby[j]];
        }
    }
    m * m
}

/// Second physical derivatives (∂xx, ∂xy, ∂yy) of the tensor basis at (ξ, η).
pub fn shape_second(
    basis: Basis1d,
    p: usize,
    h: f64,
    xi: f64,
    eta: f64,
    d2: &mut [[f64; 3]],
) -> usize {
    let (bx, dbx, d2bx) = basis.eval(p, xi);
    let (by, dby, d2by) = basis.eval(p, eta);
    let sc = 2.0 / h;
    let m = p + 1;
    for j in 0..m {
        for i in 0..m {
            d2[i + m * j] = [
                sc * sc * d2bx[i] * by[j],
                sc * sc * dbx[i] * dby[j],
                sc * sc * bx[i] * d2by[j],
            ];
        }
    }
    m * m
}
