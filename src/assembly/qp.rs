//! Per-quadrature-point storage, laid out cell by cell (CSR offsets), for history variables
//! and output fields. With the structured annulus, [`crate::mesh::RingLayout::qp_ring`] maps a
//! (cell, point) pair to its ring and position, so a streamline is walked by visiting the cells
//! of one radial layer in order ([`QpHistory::ring`]).
//!
//! Point numbering inside a cell follows the tensor Gauss rule of the element kernels
//! ([`crate::element::QuadRule::gauss_2d`]): point `l · q + i` sits at `(ξ_i, η_l)`, `i` along ξ
//! (radial on the annulus) and `l` along η (counter-clockwise).

use crate::mesh::RingLayout;

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
}
