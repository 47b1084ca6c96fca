//! Point location in a mesh: which cell holds a reference point X, and at which (ξ, η).
//!
//! A uniform grid of buckets over the mesh's bounding box lists the cells whose (slightly
//! enlarged) bounding boxes touch each bucket. For a query point, every cell of its bucket is
//! tried: the isoparametric map X(ξ, η) = Σ N_a(ξ, η) X_a is inverted by Newton's method, and the
//! cell whose reference point is innermost (smallest max(|ξ|, |η|)) wins. A point slightly
//! outside the mesh (a point on the exact circle next to a Q2 boundary arc, which deviates from
//! the circle by O(h³)) is accepted with max(|ξ|, |η|) ≤ 1 + [`EXTRAPOLATION`]: the cell's
//! polynomial is then evaluated just outside [-1, 1]².

use super::Mesh;
use crate::element::{Lagrange2D, Q1, Q2};
use crate::math::{Mat2, Vec2};

/// How far outside [-1, 1]² a located point may be (in reference coordinates).
pub const EXTRAPOLATION: f64 = 0.05;

pub struct PointLocator {
    lo: Vec2,
    h: Vec2,
    nx: usize,
    ny: usize,
    /// CSR: cells of bucket b are `cells[start[b]..start[b + 1]]`.
    start: Vec<usize>,
    cells: Vec<u32>,
}

impl PointLocator {
    pub fn new(mesh: &Mesh) -> Self {
        let n_cells = mesh.n_cells().max(1);
        let mut lo = Vec2::repeat(f64::INFINITY);
        let mut hi = Vec2::repeat(f64::NEG_INFINITY);
        for x in &mesh.nodes {
            lo = lo.inf(x);
            hi = hi.sup(x);
        }
        if !lo.iter().all(|v| v.is_finite()) {
            lo = Vec2::zeros();
            hi = Vec2::repeat(1.0);
        }
        let ext = (hi - lo).map(|v| v.max(f64::MIN_POSITIVE));
        // About one cell per bucket.
        let side = (ext[0] * ext[1] / n_cells as f64).sqrt().max(1e-300);
        let nx = ((ext[0] / side).ceil() as usize).clamp(1, 4096);
        let ny = ((ext[1] / side).ceil() as usize).clamp(1, 4096);
        let h = Vec2::new(ext[0] / nx as f64, ext[1] / ny as f64);
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); nx * ny];
        for c in 0..mesh.n_cells() {
            let (mut a, mut b) = (Vec2::repeat(f64::INFINITY), Vec2::repeat(f64::NEG_INFINITY));
            for &n in mesh.cell_nodes(c) {
                a = a.inf(&mesh.nodes[n as usize]);
                b = b.sup(&mesh.nodes[n as usize]);
            }
            // Curved sides bulge beyond the nodes' box: enlarge by a quarter of its size.
            let m = (b - a) * 0.25;
            let (a, b) = (a - m, b + m);
            let (i0, j0) = bucket_of(lo, h, nx, ny, a);
            let (i1, j1) = bucket_of(lo, h, nx, ny, b);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    lists[i + nx * j].push(c as u32);
                }
            }
        }
        let mut start = vec![0];
        let mut cells = Vec::new();
        for l in lists {
            cells.extend(l);
            start.push(cells.len());
        }
        Self {
            lo,
            h,
            nx,
            ny,
            start,
            cells,
        }
    }

    /// Cell and reference coordinates of `x`, or `None` when no cell holds it (within
    /// [`EXTRAPOLATION`]).
    pub fn locate(&self, mesh: &Mesh, x: Vec2) -> Option<(usize, f64, f64)> {
        let (i, j) = bucket_of(self.lo, self.h, self.nx, self.ny, x);
        let b = i + self.nx * j;
        let mut best: Option<(f64, usize, f64, f64)> = None;
        for &c in &self.cells[self.start[b]..self.start[b + 1]] {
            let c = c as usize;
            if let Some((xi, eta)) = inverse_map(mesh, c, x) {
                let d = xi.abs().max(eta.abs());
                if best.is_none_or(|(bd, ..)| d < bd) {
                    best = Some((d, c, xi, eta));
                }
                if d <= 1.0 {
                    break;
                }
            }
        }
        best.filter(|b| b.0 <= 1.0 + EXTRAPOLATION)
            .map(|(_, c, xi, eta)| (c, xi, eta))
    }
}

impl PointLocator {
    /// As [`Self::locate`], but always returns a cell: when no cell holds `x` within
    /// [`EXTRAPOLATION`], the cell whose reference point is innermost, with (ξ, η) clamped to
    /// [-1, 1]² (or cell 0 at its centre for an empty bucket). For points known to lie in the
    /// domain up to round-off (rotated mesh nodes).
    pub fn locate_nearest(&self, mesh: &Mesh, x: Vec2) -> (usize, f64, f64) {
        if let Some(r) = self.locate(mesh, x) {
            return r;
        }
        let (i, j) = bucket_of(self.lo, self.h, self.nx, self.ny, x);
        let b = i + self.nx * j;
        let mut best = (f64::INFINITY, 0, 0.0, 0.0);
        for &c in &self.cells[self.start[b]..self.start[b + 1]] {
            let c = c as usize;
            if let Some((xi, eta)) = inverse_map(mesh, c, x) {
                let d = xi.abs().max(eta.abs());
                if d < best.0 {
                    best = (d, c, xi.clamp(-1.0, 1.0), eta.clamp(-1.0, 1.0));
                }
            }
        }
        (best.1, best.2, best.3)
    }
}

fn bucket_of(lo: Vec2, h: Vec2, nx: usize, ny: usize, x: Vec2) -> (usize, usize) {
    let f = |v: f64, n: usize| -> usize {
        if v.is_finite() && v > 0.0 {
            (v as usize).min(n - 1)
        } else {
            0
        }
    };
    (f((x[0] - lo[0]) / h[0], nx), f((x[1] - lo[1]) / h[1], ny))
}

/// Shape values of cell `c` (tensor order) at (ξ, η), into `n` (length ≥ 9).
pub fn shape_values(mesh: &Mesh, c: usize, xi: f64, eta: f64, n: &mut [f64; 9]) {
    let mut dn = [[0.0; 2]; 9];
    if mesh.degree[c] == 1 {
        Q1::eval(xi, eta, &mut n[..4], &mut dn[..4]);
    } else {
        Q2::eval(xi, eta, &mut n[..], &mut dn[..]);
    }
}

/// Position of reference point (ξ, η) of cell `c`: the exact polar map of a polar cell, the
/// interpolation of the node positions otherwise.
pub fn point_at(mesh: &Mesh, c: usize, xi: f64, eta: f64) -> Vec2 {
    if let Some((x, _)) = mesh.geometry[c].polar_map(xi, eta) {
        return x;
    }
    let mut n = [0.0; 9];
    shape_values(mesh, c, xi, eta, &mut n);
    mesh.cell_nodes(c)
        .iter()
        .zip(&n)
        .fold(Vec2::zeros(), |s, (&node, &w)| {
            s + mesh.nodes[node as usize] * w
        })
}

/// A field with two components per node (`x[2 n + i]`, e.g. displacements) evaluated at
/// (ξ, η) of cell `c`.
pub fn vector_at(mesh: &Mesh, x: &[f64], c: usize, xi: f64, eta: f64) -> Vec2 {
    let mut n = [0.0; 9];
    shape_values(mesh, c, xi, eta, &mut n);
    mesh.cell_nodes(c)
        .iter()
        .zip(&n)
        .fold(Vec2::zeros(), |u, (&node, &w)| {
            let k = 2 * node as usize;
            u + Vec2::new(x[k], x[k + 1]) * w
        })
}

/// Newton inversion of the isoparametric map of cell `c`; `None` if it does not converge.
pub fn inverse_map(mesh: &Mesh, c: usize, x: Vec2) -> Option<(f64, f64)> {
    let cn = mesh.cell_nodes(c);
    let mut n = [0.0; 9];
    let mut dn = [[0.0; 2]; 9];
    let (mut xi, mut eta) = (0.0, 0.0);
    let scale = (mesh.nodes[cn[0] as usize] - mesh.nodes[cn[cn.len() - 1] as usize]).norm();
    for _ in 0..30 {
        if mesh.degree[c] == 1 {
            Q1::eval(xi, eta, &mut n[..4], &mut dn[..4]);
        } else {
            Q2::eval(xi, eta, &mut n, &mut dn);
        }
        let mut p = Vec2::zeros();
        let mut j = Mat2::zeros();
        for (a, &node) in cn.iter().enumerate() {
            let xa = mesh.nodes[node as usize];
            p += xa * n[a];
            j[(0, 0)] += xa[0] * dn[a][0];
            j[(0, 1)] += xa[0] * dn[a][1];
            j[(1, 0)] += xa[1] * dn[a][0];
            j[(1, 1)] += xa[1] * dn[a][1];
        }
        let r = x - p;
        if r.norm() <= 1e-13 * scale.max(f64::MIN_POSITIVE) {
            return Some((xi, eta));
        }
        let d = j.try_inverse()? * r;
        xi = (xi + d[0]).clamp(-3.0, 3.0);
        eta = (eta + d[1]).clamp(-3.0, 3.0);
    }
    // Not converged to round-off: accept a small residual (far points clamp and fail).
    let mut p = Vec2::zeros();
    shape_values(mesh, c, xi, eta, &mut n);
    for (a, &node) in cn.iter().enumerate() {
        p += mesh.nodes[node as usize] * n[a];
    }
    ((x - p).norm() <= 1e-9 * scale.max(f64::MIN_POSITIVE)).then_some((xi, eta))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{annulus, AnnulusSpec};

    #[test]
    fn locates_node_positions_and_interior_points() {
        for p in [1, 2] {
            let mut m = annulus(&AnnulusSpec {
                ri: 0.5,
                ro: 2.0,
                n_r: 3,
                n_theta: 16,
                degree: p,
                grading_r: 1.5,
                grading_theta: 0.3,
            });
            m.make_isoparametric();
            let loc = PointLocator::new(&m);
            // Every cell's centre (ξ = η = 0) is found in that cell.
            let mut n = [0.0; 9];
            for c in 0..m.n_cells() {
                shape_values(&m, c, 0.3, -0.4, &mut n);
                let x: Vec2 = m
                    .cell_nodes(c)
                    .iter()
                    .enumerate()
                    .map(|(a, &k)| m.nodes[k as usize] * n[a])
                    .sum();
                let (cc, xi, eta) = loc.locate(&m, x).expect("located");
                assert_eq!(cc, c);
                assert!((xi - 0.3).abs() < 1e-10 && (eta + 0.4).abs() < 1e-10);
            }
            // A node rotated onto the exact outer circle is found (possibly just outside).
            let x = Vec2::new(2.0 * 0.1f64.cos(), 2.0 * 0.1f64.sin());
            assert!(loc.locate(&m, x).is_some());
            // Points outside the annulus are not.
            assert!(loc.locate(&m, Vec2::new(0.0, 0.0)).is_none());
            assert!(loc.locate(&m, Vec2::new(2.5, 0.0)).is_none());
        }
    }
}
