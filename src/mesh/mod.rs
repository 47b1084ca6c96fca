//! Meshes of quadrilateral cells with a per-cell polynomial degree and exact geometry.
//!
//! A [`Mesh`] stores reference (undeformed) node positions, a CSR connectivity (so cells of
//! different degree can coexist: p-refinement), a per-cell geometry map, named node sets and
//! named facet sets. The structured annulus generator ([`annulus`]) numbers nodes ring by ring,
//! so that each ring of nodes — and each ring of quadrature points — is a closed streamline of
//! the spinning body (see [`RingLayout`]). Meshes read from Gmsh files ([`gmsh`]) have no ring
//! structure (`rings == None`): every code path that needs rings has a fallback or says so.
//!
//! Regions: each cell carries a region index ([`Mesh::regions`], names in
//! [`Mesh::region_names`]); the material of a cell is that of its region. Named boundaries are
//! the facet sets (`hub`: bonded to the rigid hub, `outer`: where contact can happen) and the
//! node sets of their nodes.

pub mod annulus;
pub mod gmsh;
pub mod gmsh3d;
pub mod hex_mesh;
pub mod locate;
pub mod locate3d;
pub mod refine;
pub mod revolved;

use crate::math::{Mat2, Vec2};
use std::collections::BTreeMap;

pub use annulus::{annulus, annulus_with_breaks, AnnulusSpec};
pub use refine::{Forest, NodeConstraint};

/// Geometry map of a cell from the reference square [-1, 1]² to the reference configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CellGeometry {
    /// Exact polar map: X(ξ, η) = r(ξ) (cos θ(η), sin θ(η)), with r and θ affine in ξ and η,
    /// r from `r0` (ξ = -1) to `r1` (ξ = 1), θ from `t0` (η = -1) to `t1` (η = 1).
    Polar { r0: f64, r1: f64, t0: f64, t1: f64 },
    /// Isoparametric: X = Σ N_a X_a with the cell's own shape functions.
    Isoparametric,
}

impl CellGeometry {
    /// Position and Jacobian dX/d(ξ, η) (columns: ∂X/∂ξ, ∂X/∂η) of a polar cell.
    /// Returns `None` for isoparametric cells (the caller interpolates node positions).
    #[inline]
    pub fn polar_map(&self, xi: f64, eta: f64) -> Option<(Vec2, Mat2)> {
        match *self {
            CellGeometry::Polar { r0, r1, t0, t1 } => {
                let r = r0 + 0.5 * (r1 - r0) * (1.0 + xi);
                let t = t0 + 0.5 * (t1 - t0) * (1.0 + eta);
                let (s, c) = t.sin_cos();
                let dr = 0.5 * (r1 - r0);
                let dt = 0.5 * (t1 - t0);
                let x = Vec2::new(r * c, r * s);
                let jac = Mat2::new(dr * c, -r * s * dt, dr * s, r * c * dt);
                Some((x, jac))
            }
            CellGeometry::Isoparametric => None,
        }
    }
}

/// Ring structure of a structured annular mesh: node `ring · per_ring + pos`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RingLayout {
    /// Number of node rings (radial node lines), innermost first.
    pub rings: usize,
    /// Nodes per ring (counter-clockwise).
    pub per_ring: usize,
    /// Cells in the radial and circumferential directions; cell `j · n_theta + k`.
    pub n_r: usize,
    pub n_theta: usize,
    /// Polynomial degree used to build the structure.
    pub degree: usize,
}

impl RingLayout {
    /// Ring and position along the ring of quadrature point `(i, l)` (i along ξ, l along η,
    /// `q` points per direction) of cell `c`: quadrature points with the same ring index lie on
    /// one circle and are ordered counter-clockwise by position.
    pub fn qp_ring(&self, cell: usize, q: usize, i: usize, l: usize) -> (usize, usize) {
        let (j, k) = (cell / self.n_theta, cell % self.n_theta);
        (j * q + i, k * q + l)
    }
}

/// A facet of a cell: the side ξ = ±1 or η = ±1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Facet {
    pub cell: u32,
    /// 0: ξ = -1, 1: ξ = +1, 2: η = -1, 3: η = +1.
    pub side: u8,
}

impl Facet {
    /// Local (tensor-order) nodes of this side of a degree-`p` cell, in the order of the side's
    /// parameter s (η on sides 0 and 1, ξ on sides 2 and 3); the first `p + 1` entries are used.
    #[inline]
    pub fn local_nodes(&self, p: usize) -> [usize; 3] {
        let m = p + 1;
        let mut out = [0; 3];
        for (k, o) in out.iter_mut().enumerate().take(m) {
            *o = match self.side {
                0 => m * k,
                1 => p + m * k,
                2 => k,
                _ => k + m * p,
            };
        }
        out
    }
    /// Reference point (ξ, η) of the side at parameter s ∈ [-1, 1].
    #[inline]
    pub fn ref_point(&self, s: f64) -> (f64, f64) {
        match self.side {
            0 => (-1.0, s),
            1 => (1.0, s),
            2 => (s, -1.0),
            _ => (s, 1.0),
        }
    }
    /// Column of dX/d(ξ, η) tangent to the side: 1 (∂X/∂η) on sides 0 and 1, 0 on 2 and 3.
    #[inline]
    pub fn tangent_column(&self) -> usize {
        if self.side < 2 {
            1
        } else {
            0
        }
    }
}

#[derive(Clone, Debug)]
pub struct Mesh {
    pub nodes: Vec<Vec2>,
    /// CSR connectivity: nodes of cell `c` are `conn[offsets[c]..offsets[c + 1]]`, local order
    /// as in [`crate::element`].
    pub conn: Vec<u32>,
    pub offsets: Vec<usize>,
    /// Polynomial degree of each cell (1 or 2).
    pub degree: Vec<u8>,
    pub geometry: Vec<CellGeometry>,
    pub node_sets: BTreeMap<String, Vec<u32>>,
    pub facet_sets: BTreeMap<String, Vec<Facet>>,
    pub rings: Option<RingLayout>,
    /// Region index of each cell (into `region_names`).
    pub regions: Vec<u16>,
    /// Region names; the generator's single region is `"all"`.
    pub region_names: Vec<String>,
    /// Hanging-node constraints of a locally refined mesh ([`refine`]): the displacement of
    /// each listed node is the given combination of its masters' (none are constrained).
    pub constraints: Vec<NodeConstraint>,
}

impl Mesh {
    /// Largest distance of a node from the axis (the outer radius of the annulus).
    pub fn outer_radius(&self) -> f64 {
        self.nodes.iter().map(|x| x.norm()).fold(0.0, f64::max)
    }

    pub fn n_nodes(&self) -> usize {
        self.nodes.len()
    }
    pub fn n_cells(&self) -> usize {
        self.degree.len()
    }
    #[inline]
    pub fn cell_nodes(&self, c: usize) -> &[u32] {
        &self.conn[self.offsets[c]..self.offsets[c + 1]]
    }
    /// Node set by name, or an empty slice.
    pub fn node_set(&self, name: &str) -> &[u32] {
        self.node_sets.get(name).map(Vec::as_slice).unwrap_or(&[])
    }
    pub fn facet_set(&self, name: &str) -> &[Facet] {
        self.facet_sets.get(name).map(Vec::as_slice).unwrap_or(&[])
    }
    /// Switch every cell to the isoparametric map (nodes stay on the exact circles; the geometry
    /// between nodes is interpolated by the cell's own shape functions). Unlike the exact polar
    /// map, the isoparametric map reproduces every linear displacement field, in particular a
    /// rigid rotation u = (Q − I) X: a rotated body carries no stress (objectivity of the
    /// discretisation, needed by the transient mode, where the body turns through large
    /// angles). With the polar map a nodal rotation by 0.3 rad leaves residual forces of
    /// ~1e-3 of the typical nodal force on a 2 × 32 mesh.
    pub fn make_isoparametric(&mut self) {
        self.geometry
            .iter_mut()
            .for_each(|g| *g = CellGeometry::Isoparametric);
    }

    /// Greedy colouring of the cells such that no two cells of one colour share a node.
    /// Cells of one colour can be assembled in parallel without write conflicts.
    pub fn color_cells(&self) -> Vec<Vec<u32>> {
        let mut node_colors = vec![0u64; self.n_nodes()];
        let mut colors: Vec<Vec<u32>> = Vec::new();
        for c in 0..self.n_cells() {
            let used = self
                .cell_nodes(c)
                .iter()
                .fold(0u64, |m, &n| m | node_colors[n as usize]);
            let color = (!used).trailing_zeros() as usize;
            // 64 colours are far more than any quadrilateral mesh needs (a structured one needs 4).
            let color = color.min(63);
            if colors.len() <= color {
                colors.resize_with(color + 1, Vec::new);
            }
            colors[color].push(c as u32);
            for &n in self.cell_nodes(c) {
                node_colors[n as usize] |= 1 << color;
            }
        }
        colors
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coloring_has_no_conflicts() {
        let m = annulus(&AnnulusSpec {
            ri: 1.0,
            ro: 2.0,
            n_r: 3,
            n_theta: 10,
            degree: 2,
            grading_r: 1.0,
            grading_theta: 0.0,
        });
        let colors = m.color_cells();
        assert!(colors.len() <= 6, "too many colours: {}", colors.len());
        let total: usize = colors.iter().map(Vec::len).sum();
        assert_eq!(total, m.n_cells());
        for group in &colors {
            let mut seen = vec![false; m.n_nodes()];
            for &c in group {
                for &n in m.cell_nodes(c as usize) {
                    assert!(!seen[n as usize], "node {n} shared within a colour");
                    seen[n as usize] = true;
                }
            }
        }
    }
}
