//! Per-quadrature-point storage, laid out cell by cell (CSR offsets), for history variables
//! and output fields. With the structured annulus, [`crate::mesh::RingLayout::qp_ring`] maps a
//! (cell, point) pair to its ring and position, so a streamline is walked by visiting the cells
//! of one radial layer in order ([`QpHistory::ring`]).
//!
//! Point numbering inside a cell follows the tensor Gauss rule of the element kernels
//! ([`crate::element::QuadRule::gauss_2d`]): point `l · q + i` sits at `(ξ_i, η_l)`, `i` along ξ
//! (radial on the annulus) and `l` along η (counter-clockwise).

use crate::element::gauss_1d;
use crate::mesh::locate::{point_at, PointLocator};
use crate::mesh::{Mesh, RingLayout};

#[derive(Clone, Debug)]
pub struct QpData<T> {
    pub offsets: Vec<usize>,
    pub data: Vec<T>,
}

impl<T: Clone> QpData<T> {
    /// `per_cell[c]` points in cell `c`, all initialised to `init`.
    pub fn new(per_cell: impl IntoIterator<Item = usize>, init: T) -> Self {
        let mut offsets = vec![0];
        for n in per_cell {
            let last = *offsets.last().unwrap_or(&0);
            offsets.push(last + n);
        }
        let total = *offsets.last().unwrap_or(&0);
        Self {
            offsets,
            data: vec![init; total],
        }
    }
    pub fn cell(&self, c: usize) -> &[T] {
        &self.data[self.offsets[c]..self.offsets[c + 1]]
    }
    pub fn cell_mut(&mut self, c: usize) -> &mut [T] {
        &mut self.data[self.offsets[c]..self.offsets[c + 1]]
    }
}

/// History of a stateful material: `n_state` values per quadrature point, cell by cell.
/// Empty (no allocation, `n_state = 0`) for elastic materials.
#[derive(Clone, Debug, Default)]
pub struct QpHistory {
    /// Values per point.
    pub n_state: usize,
    /// First point of each cell (`n_cells + 1` entries; empty when there is no history).
    pub offsets: Vec<usize>,
    /// `n_state` values per point, points in cell order.
    pub data: Vec<f64>,
}

impl QpHistory {
    /// No history.
    pub fn none() -> Self {
        Self::default()
    }

    /// `points_per_cell[c]` points in cell `c`, each starting from the state `init`
    /// (`n_state = init.len()`).
    pub fn new(points_per_cell: impl IntoIterator<Item = usize>, init: &[f64]) -> Self {
        let n_state = init.len();
        if n_state == 0 {
            return Self::none();
        }
        let mut offsets = vec![0];
        for n in points_per_cell {
            let last = *offsets.last().unwrap_or(&0);
            offsets.push(last + n);
        }
        let total = *offsets.last().unwrap_or(&0);
        let mut data = Vec::with_capacity(total * n_state);
        for _ in 0..total {
            data.extend_from_slice(init);
        }
        Self {
            n_state,
            offsets,
            data,
        }
    }

    /// Whether there is any history to keep.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.n_state == 0
    }

    /// Number of points of cell `c`.
    pub fn points_in_cell(&self, c: usize) -> usize {
        self.offsets[c + 1] - self.offsets[c]
    }

    /// The state of every point of cell `c` (`points_in_cell(c) · n_state` values).
    pub fn cell(&self, c: usize) -> &[f64] {
        &self.data[self.offsets[c] * self.n_state..self.offsets[c + 1] * self.n_state]
    }

    /// Mutable state of every point of cell `c`.
    pub fn cell_mut(&mut self, c: usize) -> &mut [f64] {
        &mut self.data[self.offsets[c] * self.n_state..self.offsets[c + 1] * self.n_state]
    }

    /// The state of point `q` of cell `c`.
    #[inline]
    pub fn point(&self, c: usize, q: usize) -> &[f64] {
        let s = (self.offsets[c] + q) * self.n_state;
        &self.data[s..s + self.n_state]
    }

    /// Mutable state of point `q` of cell `c`.
    #[inline]
    pub fn point_mut(&mut self, c: usize, q: usize) -> &mut [f64] {
        let s = (self.offsets[c] + q) * self.n_state;
        &mut self.data[s..s + self.n_state]
    }

    /// The points of ring `ring` of a ring-structured mesh with `q` Gauss points per direction
    /// in every cell, in counter-clockwise order, as `(cell, point)` pairs: the streamline of
    /// the steady mode. The inverse of [`RingLayout::qp_ring`].
    pub fn ring(
        layout: &RingLayout,
        q: usize,
        ring: usize,
    ) -> impl Iterator<Item = (usize, usize)> + '_ {
        let (j, i) = (ring / q, ring % q);
        (0..layout.n_theta * q).map(move |pos| {
            let (k, l) = (pos / q, pos % q);
            (j * layout.n_theta + k, l * q + i)
        })
    }

    /// Number of rings of quadrature points on a ring-structured mesh (`q` points per
    /// direction).
    pub fn n_rings(layout: &RingLayout, q: usize) -> usize {
        layout.n_r * q
    }
}

/// Why a history cannot be moved to another mesh ([`QpHistory::transferred`]).
#[derive(Clone, Debug, PartialEq)]
pub enum TransferError {
    /// A cell of the source holds another number of points than the tensor Gauss rule of its
    /// degree ((p + 1)² for degree p), or the source does not match its mesh.
    NotTensorGauss { cell: usize, points: usize },
}

impl std::fmt::Display for TransferError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NotTensorGauss { cell, points } => write!(
                f,
                "cell {cell} of the source mesh holds {points} history points, not the tensor \
                 Gauss rule of its degree"
            ),
        }
    }
}

impl std::error::Error for TransferError {}

/// Lagrange basis through the points `nodes` at `s`, into `out`.
fn lagrange(nodes: &[f64], s: f64, out: &mut [f64]) {
    for (i, (o, &si)) in out.iter_mut().zip(nodes).enumerate() {
        *o = nodes
            .iter()
            .enumerate()
            .filter(|&(j, _)| j != i)
            .map(|(_, &sj)| (s - sj) / (si - sj))
            .product();
    }
}

impl QpHistory {
    /// The history on another mesh `to` of the same body (a refined or coarsened one): every
    /// point of `to` (the tensor Gauss rule of its cell's degree p, q = p + 1 points per
    /// direction, as the element kernels use) takes the value at its position of the
    /// tensor-product Lagrange interpolant through the points of the `from` cell that holds it
    /// (degree q − 1 in each reference direction). Exact for states that are such polynomials
    /// of the `from` cell's reference coordinates (in particular when `to` refines or coarsens
    /// `from` by whole cells and the state is one polynomial per parent cell; constants
    /// always); otherwise an interpolation error of order h^q. Tensor states are moved
    /// component by component in the common Cartesian frame.
    pub fn transferred(&self, from: &Mesh, to: &Mesh) -> Result<QpHistory, TransferError> {
        if self.is_empty() {
            return Ok(Self::none());
        }
        let q_of = |mesh: &Mesh, c: usize| usize::from(mesh.degree[c]) + 1;
        if self.offsets.len() != from.n_cells() + 1 {
            return Err(TransferError::NotTensorGauss {
                cell: 0,
                points: self.offsets.len().saturating_sub(1),
            });
        }
        for c in 0..from.n_cells() {
            let q = q_of(from, c);
            if self.points_in_cell(c) != q * q {
                return Err(TransferError::NotTensorGauss {
                    cell: c,
                    points: self.points_in_cell(c),
                });
            }
        }
        let init = vec![0.0; self.n_state];
        let mut out = Self::new((0..to.n_cells()).map(|c| q_of(to, c).pow(2)), &init);
        let locator = PointLocator::new(from);
        let (mut lx, mut ly) = ([0.0; 4], [0.0; 4]);
        for c in 0..to.n_cells() {
            let q = q_of(to, c);
            let (g, _) = gauss_1d(q);
            for l in 0..q {
                for i in 0..q {
                    let x = point_at(to, c, g[i], g[l]);
                    let (src, xi, eta) = locator.locate_nearest(from, x);
                    let qs = q_of(from, src);
                    let (gs, _) = gauss_1d(qs);
                    lagrange(&gs, xi, &mut lx[..qs]);
                    lagrange(&gs, eta, &mut ly[..qs]);
                    let n = self.n_state;
                    let dst = out.point_mut(c, l * q + i);
                    for (ls, wy) in ly[..qs].iter().enumerate() {
                        for (is, wx) in lx[..qs].iter().enumerate() {
                            let v = self.point(src, ls * qs + is);
                            for k in 0..n {
                                dst[k] += wx * wy * v[k];
                            }
                        }
                    }
                }
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::annulus::{annulus, AnnulusSpec};

    #[test]
    fn cell_and_ring_walks_cover_every_point_once() {
        let mesh = annulus(&AnnulusSpec {
            ri: 1.0,
            ro: 2.0,
            n_r: 3,
            n_theta: 8,
            degree: 2,
            grading_r: 1.0,
            grading_theta: 0.0,
        });
        let layout = mesh.rings.expect("structured annulus has rings");
        let q = 3;
        let mut h = QpHistory::new((0..mesh.n_cells()).map(|_| q * q), &[0.0, 0.0]);
        assert_eq!(h.data.len(), mesh.n_cells() * q * q * 2);
        // Mark each point by its cell walk, then visit by rings.
        for c in 0..mesh.n_cells() {
            for p in 0..q * q {
                h.point_mut(c, p)[0] = (c * 100 + p) as f64;
            }
        }
        let mut seen = vec![0; h.data.len() / 2];
        for r in 0..QpHistory::n_rings(&layout, q) {
            let pts: Vec<(usize, usize)> = QpHistory::ring(&layout, q, r).collect();
            assert_eq!(pts.len(), layout.n_theta * q);
            for (pos, &(c, p)) in pts.iter().enumerate() {
                assert_eq!(h.point(c, p)[0], (c * 100 + p) as f64);
                // The inverse of qp_ring.
                assert_eq!(layout.qp_ring(c, q, p % q, p / q), (r, pos));
                seen[h.offsets[c] + p] += 1;
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
        // The points of one ring are at one radius and go counter-clockwise.
        let tab = crate::element::ShapeTable::<9>::gauss::<crate::element::Q2>(q);
        for r in [0, 4, 8] {
            let xs: Vec<crate::math::Vec2> = QpHistory::ring(&layout, q, r)
                .map(|(c, p)| {
                    let (xi, eta) = tab.points[p];
                    mesh.geometry[c].polar_map(xi, eta).unwrap().0
                })
                .collect();
            let r0 = xs[0].norm();
            assert!(xs.iter().all(|x| (x.norm() - r0).abs() < 1e-12));
            let ang: Vec<f64> = xs.iter().map(|x| x[1].atan2(x[0])).collect();
            let mut turns = 0.0;
            for w in 0..xs.len() {
                let mut d = ang[(w + 1) % xs.len()] - ang[w];
                if d < -std::f64::consts::PI {
                    d += 2.0 * std::f64::consts::PI;
                }
                assert!(d > 0.0);
                turns += d;
            }
            assert!((turns - 2.0 * std::f64::consts::PI).abs() < 1e-12);
        }
        // Elastic: no storage at all.
        let e = QpHistory::new((0..mesh.n_cells()).map(|_| 9), &[]);
        assert!(e.is_empty() && e.data.capacity() == 0 && e.offsets.is_empty());
    }

    /// A state that is one polynomial of degree q − 1 per direction in each root cell's
    /// reference coordinates moves exactly to the refined mesh and back; a constant moves
    /// exactly to an unrelated mesh.
    #[test]
    fn history_transfer_is_exact_for_the_interpolated_polynomials() {
        use crate::mesh::Forest;
        let spec = |n_theta| AnnulusSpec {
            ri: 1.0,
            ro: 2.0,
            n_r: 2,
            n_theta,
            degree: 2,
            grading_r: 1.0,
            grading_theta: 0.0,
        };
        let mut root = annulus(&spec(8));
        root.make_isoparametric();
        let p = |c: usize, xi: f64, eta: f64| -> [f64; 2] {
            let c = c as f64;
            [
                1.0 + c + xi - 2.0 * eta + 0.5 * xi * eta + xi * xi - 0.25 * eta * eta * xi,
                -3.0,
            ]
        };
        let (g, _) = gauss_1d(3);
        let mut h = QpHistory::new((0..root.n_cells()).map(|_| 9), &[0.0, 0.0]);
        for c in 0..root.n_cells() {
            for l in 0..3 {
                for i in 0..3 {
                    h.point_mut(c, l * 3 + i).copy_from_slice(&p(c, g[i], g[l]));
                }
            }
        }
        let mut forest = Forest::new(root.clone()).unwrap();
        forest.refine(&[0, 3, 4]).unwrap();
        forest.refine(&[0]).unwrap();
        let (fine, _) = forest.mesh();
        assert!(!fine.constraints.is_empty());
        let hf = h.transferred(&root, &fine).unwrap();
        let mut worst = 0.0f64;
        for (c, leaf) in forest.leaves().iter().enumerate() {
            for l in 0..3 {
                for i in 0..3 {
                    let (a, b) = leaf.to_root(g[i], g[l]);
                    let want = p(leaf.root as usize, a, b);
                    let got = hf.point(c, l * 3 + i);
                    worst = worst
                        .max((got[0] - want[0]).abs())
                        .max((got[1] - want[1]).abs());
                }
            }
        }
        assert!(worst < 1e-11, "refined: {worst:e}");
        // Back to the root mesh: the children's polynomials are the parent's.
        let back = hf.transferred(&fine, &root).unwrap();
        let diff = back
            .data
            .iter()
            .zip(&h.data)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(diff < 1e-11, "back: {diff:e}");
        // A constant onto an unrelated mesh.
        let c = QpHistory::new((0..root.n_cells()).map(|_| 9), &[2.5, -1.0, 0.0]);
        let mut other = annulus(&spec(12));
        other.make_isoparametric();
        let co = c.transferred(&root, &other).unwrap();
        assert_eq!(co.data.len(), other.n_cells() * 9 * 3);
        assert!(co.data.chunks(3).all(|v| (v[0] - 2.5).abs() < 1e-12
            && (v[1] + 1.0).abs() < 1e-12
            && v[2].abs() < 1e-12));
        // A history that does not fit the mesh is refused.
        let wrong = QpHistory::new((0..root.n_cells()).map(|_| 4), &[1.0]);
        assert_eq!(
            wrong.transferred(&root, &other).err(),
            Some(TransferError::NotTensorGauss { cell: 0, points: 4 })
        );
    }
}
