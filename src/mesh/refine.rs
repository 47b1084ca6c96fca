//! Local h-refinement of a quadrilateral mesh: a quadtree on every cell of a root mesh, kept
//! one-irregular, and the hanging-node constraints of the refined mesh.
//!
//! A [`Forest`] holds the root [`Mesh`] and its leaves. A leaf is the sub-square
//! [−1 + 2i/2ˡ, −1 + 2(i+1)/2ˡ] × [−1 + 2j/2ˡ, −1 + 2(j+1)/2ˡ] of its root cell's reference
//! square at level l; its geometry is the root's map restricted to it (a polar root gives polar
//! children, exactly on the circles; an isoparametric root gives isoparametric children whose
//! nodes lie on the root's map, which the restricted Q1/Q2 map reproduces exactly). Every leaf
//! has its root's degree.
//!
//! [`Forest::mesh`] builds the leaf mesh: nodes are identified by position (quantised at 1e-10
//! of the mesh size), boundary facet sets and their node sets follow the root's, regions are the
//! roots', and the result has no ring structure. A node of a fine leaf that lies inside a side of
//! a coarser neighbour (a *hanging node*) gets the constraint u = Σ_k L_k(s) u_k, L_k the
//! Lagrange polynomials of the coarse side's nodes at the node's side parameter s (Q1: the mean
//! of the two ends; Q2: weights (−1/8, 3/4, 3/8) at s = 1/2), with chains through hanging
//! masters resolved ([`Mesh::constraints`]); the displacement field stays continuous.
//!
//! [`Forest::refine`] splits the marked leaves into four and then keeps splitting leaves that
//! have a neighbour more than one level finer (one-irregularity), so every hanging node has
//! regular or once-hanging masters. [`Forest::locate`] gives, for a root point, the leaf that
//! contains it: the transfer of a solution from one mesh of the forest to the next.

use super::{CellGeometry, Facet, Mesh};
use crate::element::{Lagrange2D, Q1, Q2};
use crate::math::Vec2;
use std::collections::{BTreeMap, HashMap};

/// A hanging node's constraint: u(node) = Σ weight · u(master).
#[derive(Clone, Debug, PartialEq)]
pub struct NodeConstraint {
    pub node: u32,
    pub masters: Vec<(u32, f64)>,
}

/// A leaf of the quadtree of root cell `root`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Leaf {
    pub root: u32,
    pub level: u8,
    pub i: u32,
    pub j: u32,
}

impl Leaf {
    /// Root reference coordinates of the leaf's point (ξ, η).
    pub fn to_root(&self, xi: f64, eta: f64) -> (f64, f64) {
        let h = 2.0 / f64::from(1u32 << self.level);
        (
            -1.0 + h * (f64::from(self.i) + 0.5 * (1.0 + xi)),
            -1.0 + h * (f64::from(self.j) + 0.5 * (1.0 + eta)),
        )
    }
    /// The leaf's local coordinates of root point (ξ, η) (outside [−1, 1]² if not in the leaf).
    pub fn from_root(&self, xi: f64, eta: f64) -> (f64, f64) {
        let h = 2.0 / f64::from(1u32 << self.level);
        (
            2.0 * ((xi + 1.0) / h - f64::from(self.i)) - 1.0,
            2.0 * ((eta + 1.0) / h - f64::from(self.j)) - 1.0,
        )
    }
    /// The leaf this one was split from (`None` for a root cell).
    pub fn parent(&self) -> Option<Leaf> {
        (self.level > 0).then(|| Leaf {
            root: self.root,
            level: self.level - 1,
            i: self.i / 2,
            j: self.j / 2,
        })
    }
    fn children(&self) -> [Leaf; 4] {
        let l = self.level + 1;
        let (i, j) = (2 * self.i, 2 * self.j);
        [
            Leaf {
                root: self.root,
                level: l,
                i,
                j,
            },
            Leaf {
                root: self.root,
                level: l,
                i: i + 1,
                j,
            },
            Leaf {
                root: self.root,
                level: l,
                i,
                j: j + 1,
            },
            Leaf {
                root: self.root,
                level: l,
                i: i + 1,
                j: j + 1,
            },
        ]
    }
    /// Whether side `side` (0: ξ = −1, 1: ξ = 1, 2: η = −1, 3: η = 1) lies on the root's side.
    fn on_root_side(&self, side: u8) -> bool {
        let last = (1u32 << self.level) - 1;
        match side {
            0 => self.i == 0,
            1 => self.i == last,
            2 => self.j == 0,
            _ => self.j == last,
        }
    }
}

/// Why a mesh cannot be refined.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum RefineError {
    #[error("local refinement needs one element degree on the whole mesh (found {0} and {1})")]
    MixedDegree(u8, u8),
    #[error("the mesh has no cells")]
    Empty,
    #[error("leaf {0} does not exist (the mesh has {1} cells)")]
    NoSuchLeaf(usize, usize),
    #[error("refinement beyond level {0}")]
    TooDeep(u8),
}

/// Deepest level of a leaf.
pub const MAX_LEVEL: u8 = 20;

/// Quadtrees over the cells of a root mesh.
#[derive(Clone, Debug)]
pub struct Forest {
    pub root: Mesh,
    leaves: Vec<Leaf>,
    /// Element degree of each leaf (1 or 2), parallel to `leaves`.
    degrees: Vec<u8>,
    tol: f64,
}

type Key = (i64, i64);

impl Forest {
    pub fn new(root: Mesh) -> Result<Self, RefineError> {
        let degree = *root.degree.first().ok_or(RefineError::Empty)?;
        if let Some(&d) = root.degree.iter().find(|&&d| d != degree) {
            return Err(RefineError::MixedDegree(degree, d));
        }
        let size = root
            .nodes
            .iter()
            .map(|x| x.norm())
            .fold(0.0, f64::max)
            .max(1e-300);
        let leaves: Vec<Leaf> = (0..root.n_cells() as u32)
            .map(|c| Leaf {
                root: c,
                level: 0,
                i: 0,
                j: 0,
            })
            .collect();
        Ok(Self {
            degrees: vec![degree; leaves.len()],
            root,
            leaves,
            tol: 1e-10 * size,
        })
    }

    /// The leaves, in the cell order of [`Self::mesh`].
    pub fn leaves(&self) -> &[Leaf] {
        &self.leaves
    }

    /// The element degree of each leaf (1 or 2), in the order of [`Self::leaves`].
    pub fn degrees(&self) -> &[u8] {
        &self.degrees
    }

    /// p-refinement: raise the degree of the given leaves (indices into [`Self::leaves`]) from 1
    /// to 2. Leaves already of degree 2 are left as they are. Returns the number raised.
    pub fn raise_degree(&mut self, marked: &[usize]) -> Result<usize, RefineError> {
        let mask = self.mask(marked)?;
        let mut raised = 0;
        for (d, m) in self.degrees.iter_mut().zip(mask) {
            if m && *d < 2 {
                *d = 2;
                raised += 1;
            }
        }
        Ok(raised)
    }

    /// Position of root point (ξ, η) of root cell `c`.
    pub fn root_point(&self, c: usize, xi: f64, eta: f64) -> Vec2 {
        super::locate::point_at(&self.root, c, xi, eta)
    }

    fn key(&self, x: Vec2) -> Key {
        (
            (x[0] / self.tol).round() as i64,
            (x[1] / self.tol).round() as i64,
        )
    }

    fn leaf_point(&self, l: &Leaf, xi: f64, eta: f64) -> Vec2 {
        let (a, b) = l.to_root(xi, eta);
        self.root_point(l.root as usize, a, b)
    }

    /// Keys of every leaf corner (the one-irregularity test looks for the corners of finer
    /// neighbours, whatever the degrees).
    fn corner_keys(&self) -> std::collections::HashSet<Key> {
        self.leaves
            .iter()
            .flat_map(|l| {
                [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)].map(|(a, b)| (l, a, b))
            })
            .map(|(l, a, b)| self.key(self.leaf_point(l, a, b)))
            .collect()
    }

    /// Split the leaves with the given indices (into [`Self::leaves`]) into four, then keep the
    /// forest one-irregular. Returns the number of leaves split.
    pub fn refine(&mut self, marked: &[usize]) -> Result<usize, RefineError> {
        let mut split = self.mask(marked)?;
        let mut total = 0;
        loop {
            let count = split.iter().filter(|&&s| s).count();
            if count == 0 {
                break;
            }
            total += count;
            let mut next = Vec::with_capacity(self.leaves.len() + 3 * count);
            let mut degrees = Vec::with_capacity(next.capacity());
            for ((l, &s), &d) in self.leaves.iter().zip(&split).zip(&self.degrees) {
                if s {
                    if l.level >= MAX_LEVEL {
                        return Err(RefineError::TooDeep(MAX_LEVEL));
                    }
                    next.extend(l.children());
                    degrees.extend([d; 4]);
                } else {
                    next.push(*l);
                    degrees.push(d);
                }
            }
            self.leaves = next;
            self.degrees = degrees;
            // One-irregularity: a leaf with a corner of a neighbour two levels finer on a side.
            let keys = self.corner_keys();
            split = self
                .leaves
                .iter()
                .map(|l| self.too_coarse(&keys, l))
                .collect();
        }
        Ok(total)
    }

    /// One flag per leaf: set for the given leaf indices (an error for an index past the end).
    fn mask(&self, marked: &[usize]) -> Result<Vec<bool>, RefineError> {
        let n = self.leaves.len();
        let mut mask = vec![false; n];
        for &k in marked {
            *mask.get_mut(k).ok_or(RefineError::NoSuchLeaf(k, n))? = true;
        }
        Ok(mask)
    }

    /// Whether leaf `l` has, inside one of its sides, a corner of a neighbour two or more
    /// levels finer (`keys`: the corner keys of the current leaves): s = ±1/2, where only such
    /// a neighbour has corners.
    fn too_coarse(&self, keys: &std::collections::HashSet<Key>, l: &Leaf) -> bool {
        (0..4u8).any(|side| {
            [-0.5, 0.5].iter().any(|&s| {
                let f = Facet { cell: 0, side };
                let (a, b) = f.ref_point(s);
                keys.contains(&self.key(self.leaf_point(l, a, b)))
            })
        })
    }

    /// Merge families of four sibling leaves back into their parent where all four are marked
    /// (indices into [`Self::leaves`]), except where the parent would break one-irregularity
    /// (a neighbour more than one level finer than the parent); such families stay split.
    /// Root cells are never merged. The parent takes the place of its first child in the leaf
    /// order. Returns the number of families merged.
    pub fn coarsen(&mut self, marked: &[usize]) -> Result<usize, RefineError> {
        use std::collections::HashMap;
        let mark = self.mask(marked)?;
        // Marked children per parent.
        let mut count: HashMap<Leaf, usize> = HashMap::new();
        for (l, &m) in self.leaves.iter().zip(&mark) {
            if let (true, Some(p)) = (m, l.parent()) {
                *count.entry(p).or_default() += 1;
            }
        }
        let mut merged: std::collections::HashSet<Leaf> = count
            .into_iter()
            .filter_map(|(p, c)| (c == 4).then_some(p))
            .collect();
        let original = self.leaves.clone();
        let original_degrees = self.degrees.clone();
        // A merged parent takes the highest degree of its children.
        let mut parent_degree: HashMap<Leaf, u8> = HashMap::new();
        for (l, &d) in original.iter().zip(&original_degrees) {
            if let Some(p) = l.parent() {
                let e = parent_degree.entry(p).or_insert(d);
                *e = (*e).max(d);
            }
        }
        loop {
            let mut next = Vec::with_capacity(original.len());
            let mut degrees = Vec::with_capacity(original.len());
            for (l, &d) in original.iter().zip(&original_degrees) {
                match l.parent().filter(|p| merged.contains(p)) {
                    Some(p) => {
                        if p.children()[0] == *l {
                            next.push(p);
                            degrees.push(parent_degree[&p]);
                        }
                    }
                    None => {
                        next.push(*l);
                        degrees.push(d);
                    }
                }
            }
            self.leaves = next;
            self.degrees = degrees;
            let keys = self.corner_keys();
            let bad: Vec<Leaf> = merged
                .iter()
                .filter(|p| self.too_coarse(&keys, p))
                .copied()
                .collect();
            if bad.is_empty() {
                return Ok(merged.len());
            }
            for p in bad {
                merged.remove(&p);
            }
        }
    }

    /// The leaf containing root point (ξ, η) of root cell `root`, and the point in its local
    /// coordinates.
    pub fn locate(&self, root: u32, xi: f64, eta: f64) -> Option<(usize, (f64, f64))> {
        const EPS: f64 = 1e-12;
        self.leaves.iter().enumerate().find_map(|(k, l)| {
            if l.root != root {
                return None;
            }
            let (a, b) = l.from_root(xi, eta);
            (a.abs() <= 1.0 + EPS && b.abs() <= 1.0 + EPS).then_some((k, (a, b)))
        })
    }

    /// The leaf mesh with its hanging-node constraints, and for every node one (root cell,
    /// root ξ, root η) where it lies.
    pub fn mesh(&self) -> (Mesh, Vec<(u32, f64, f64)>) {
        let refs = |p: u8| -> Vec<(f64, f64)> {
            let n = (usize::from(p) + 1).pow(2);
            (0..n)
                .map(|a| {
                    if p == 1 {
                        Q1::node_ref(a)
                    } else {
                        Q2::node_ref(a)
                    }
                })
                .collect()
        };
        let refs = [refs(1), refs(2)];
        let refs_of = |p: u8| &refs[usize::from(p.clamp(1, 2)) - 1];
        let mut ids: HashMap<Key, u32> = HashMap::new();
        let mut nodes: Vec<Vec2> = Vec::new();
        let mut origin: Vec<(u32, f64, f64)> = Vec::new();
        let mut conn = Vec::with_capacity(self.leaves.len() * 9);
        let mut offsets = vec![0];
        let mut geometry = Vec::with_capacity(self.leaves.len());
        for (l, &p) in self.leaves.iter().zip(&self.degrees) {
            for &(a, b) in refs_of(p) {
                let x = self.leaf_point(l, a, b);
                let id = *ids.entry(self.key(x)).or_insert_with(|| {
                    nodes.push(x);
                    let (ra, rb) = l.to_root(a, b);
                    origin.push((l.root, ra, rb));
                    (nodes.len() - 1) as u32
                });
                conn.push(id);
            }
            offsets.push(conn.len());
            geometry.push(match self.root.geometry[l.root as usize] {
                CellGeometry::Polar { r0, r1, t0, t1 } => {
                    let (x0, y0) = l.to_root(-1.0, -1.0);
                    let (x1, y1) = l.to_root(1.0, 1.0);
                    CellGeometry::Polar {
                        r0: r0 + 0.5 * (r1 - r0) * (1.0 + x0),
                        r1: r0 + 0.5 * (r1 - r0) * (1.0 + x1),
                        t0: t0 + 0.5 * (t1 - t0) * (1.0 + y0),
                        t1: t0 + 0.5 * (t1 - t0) * (1.0 + y1),
                    }
                }
                CellGeometry::Isoparametric => CellGeometry::Isoparametric,
            });
        }
        let cell = |k: usize| &conn[offsets[k]..offsets[k + 1]];
        // Facet sets from the roots' and node sets of the same names.
        let mut by_root: Vec<Vec<u32>> = vec![Vec::new(); self.root.n_cells()];
        for (k, l) in self.leaves.iter().enumerate() {
            by_root[l.root as usize].push(k as u32);
        }
        let mut facet_sets = BTreeMap::new();
        let mut node_sets = BTreeMap::new();
        for (name, facets) in &self.root.facet_sets {
            let mut out = Vec::new();
            let mut set = Vec::new();
            for f in facets {
                for &k in &by_root[f.cell as usize] {
                    if self.leaves[k as usize].on_root_side(f.side) {
                        let nf = Facet {
                            cell: k,
                            side: f.side,
                        };
                        let p = usize::from(self.degrees[k as usize]);
                        let cn = cell(k as usize);
                        set.extend(nf.local_nodes(p)[..=p].iter().map(|&a| cn[a]));
                        out.push(nf);
                    }
                }
            }
            set.sort_unstable();
            set.dedup();
            facet_sets.insert(name.clone(), out);
            node_sets.insert(name.clone(), set);
        }
        for (name, set) in &self.root.node_sets {
            if !node_sets.contains_key(name) {
                // A node set without facets: the nodes at the same positions.
                let mapped: Vec<u32> = set
                    .iter()
                    .filter_map(|&n| ids.get(&self.key(self.root.nodes[n as usize])).copied())
                    .collect();
                node_sets.insert(name.clone(), mapped);
            }
        }
        // Continuity across sides (the minimum rule). (1) A node of another leaf inside a
        // leaf's side (a finer neighbour's, or the midside node of a same-size neighbour of
        // higher degree) follows the side's trace: u = Σ L_k(s) u_k over the side's nodes.
        // Neighbours are at most one level finer and of degree ≤ 2, so their nodes inside the
        // side lie at s ∈ {0, ±1/4, ±1/2, ±3/4}.
        let mut raw: BTreeMap<u32, Vec<(u32, f64)>> = BTreeMap::new();
        for (k, (l, &pk)) in self.leaves.iter().zip(&self.degrees).enumerate() {
            let p = usize::from(pk);
            let cn = cell(k);
            for side in 0..4u8 {
                let f = Facet {
                    cell: k as u32,
                    side,
                };
                let side_nodes = f.local_nodes(p);
                for s in [-0.75, -0.5, -0.25, 0.0, 0.25, 0.5, 0.75] {
                    let (a, b) = f.ref_point(s);
                    let Some(&h) = ids.get(&self.key(self.leaf_point(l, a, b))) else {
                        continue;
                    };
                    if cn.contains(&h) {
                        continue;
                    }
                    let w = lagrange_1d_weights(p, s);
                    raw.entry(h)
                        .or_insert_with(|| (0..=p).map(|m| (cn[side_nodes[m]], w[m])).collect());
                }
            }
        }
        // (2) A degree-2 leaf whose side meets degree-1 neighbours of its size or finer (the
        // same side midpoint, or the midpoints of the two halves) has a linear trace there: its
        // midside node is the mean of the side's ends.
        let mut side_degrees: HashMap<Key, Vec<(usize, u8)>> = HashMap::new();
        for (k, (l, &pk)) in self.leaves.iter().zip(&self.degrees).enumerate() {
            for side in 0..4u8 {
                let (a, b) = Facet { cell: 0, side }.ref_point(0.0);
                side_degrees
                    .entry(self.key(self.leaf_point(l, a, b)))
                    .or_default()
                    .push((k, pk));
            }
        }
        for (k, (l, &pk)) in self.leaves.iter().zip(&self.degrees).enumerate() {
            if pk != 2 {
                continue;
            }
            let cn = cell(k);
            for side in 0..4u8 {
                let f = Facet {
                    cell: k as u32,
                    side,
                };
                let linear = [-0.5, 0.0, 0.5].iter().any(|&s| {
                    let (a, b) = f.ref_point(s);
                    side_degrees
                        .get(&self.key(self.leaf_point(l, a, b)))
                        .is_some_and(|v| v.iter().any(|&(j, d)| j != k && d == 1))
                });
                if linear {
                    let sn = f.local_nodes(2);
                    raw.entry(cn[sn[1]])
                        .or_insert_with(|| vec![(cn[sn[0]], 0.5), (cn[sn[2]], 0.5)]);
                }
            }
        }
        let constraints = resolve_chains(raw);
        let mesh = Mesh {
            nodes,
            conn,
            offsets,
            degree: self.degrees.clone(),
            geometry,
            node_sets,
            facet_sets,
            rings: None,
            regions: self
                .leaves
                .iter()
                .map(|l| self.root.regions[l.root as usize])
                .collect(),
            region_names: self.root.region_names.clone(),
            constraints,
        };
        (mesh, origin)
    }
}

/// Weights of the degree-`p` Lagrange polynomials on the equispaced points of [−1, 1] at `s`.
fn lagrange_1d_weights(p: usize, s: f64) -> [f64; 3] {
    let pts: Vec<f64> = (0..=p).map(|k| -1.0 + 2.0 * k as f64 / p as f64).collect();
    let mut w = [0.0; 3];
    for k in 0..=p {
        w[k] = (0..=p)
            .filter(|&m| m != k)
            .map(|m| (s - pts[m]) / (pts[k] - pts[m]))
            .product();
    }
    w
}

/// Substitute constrained masters until every master is unconstrained.
fn resolve_chains(raw: BTreeMap<u32, Vec<(u32, f64)>>) -> Vec<NodeConstraint> {
    let mut out = Vec::with_capacity(raw.len());
    for (&node, masters) in &raw {
        let mut terms = masters.clone();
        for _ in 0..64 {
            if !terms.iter().any(|(m, _)| raw.contains_key(m)) {
                break;
            }
            let mut next: Vec<(u32, f64)> = Vec::new();
            for &(m, w) in &terms {
                match raw.get(&m) {
                    Some(sub) => next.extend(sub.iter().map(|&(mm, ww)| (mm, w * ww))),
                    None => next.push((m, w)),
                }
            }
            next.sort_by_key(|t| t.0);
            let mut merged: Vec<(u32, f64)> = Vec::with_capacity(next.len());
            for (m, w) in next {
                match merged.last_mut() {
                    Some(last) if last.0 == m => last.1 += w,
                    _ => merged.push((m, w)),
                }
            }
            terms = merged;
        }
        terms.retain(|t| t.1 != 0.0);
        out.push(NodeConstraint {
            node,
            masters: terms,
        });
    }
    out
}
