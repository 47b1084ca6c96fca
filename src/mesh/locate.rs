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

/// [`PointLocator::locate_nearest`] of many points at once, for points that mostly lie in
/// the cell of the point before them (a mesh's nodes, in order). On a ring mesh (cell
/// j · n_theta + k, see [`super::RingLayout`]) the cell a point's radius and angle name among
/// the vertex rings and rays is tried first, then the cell of the point before, then the
/// buckets' search; a point is taken from a tried cell when it lies inside it up to round-off.
pub fn locate_points(mesh: &Mesh, points: &[Vec2]) -> Vec<(usize, f64, f64)> {
    use std::f64::consts::TAU;
    // The buckets only if some point needs them.
    let loc = std::cell::OnceCell::new();
    // The vertex rings' radii (but the innermost) and the vertex rays' angles from the first.
    let rings = mesh
        .rings
        .filter(|rl| rl.n_r > 0 && rl.n_theta > 0 && rl.degree > 0)
        .map(|rl| {
            let vertex =
                |ring: usize, k: usize| mesh.nodes[ring * rl.degree * rl.per_ring + k * rl.degree];
            let x0 = vertex(0, 0);
            let t0 = x0[1].atan2(x0[0]);
            let radii: Vec<f64> = (1..rl.n_r).map(|j| vertex(j, 0).norm()).collect();
            let angles: Vec<f64> = (1..rl.n_theta)
                .map(|k| {
                    let x = vertex(0, k);
                    (x[1].atan2(x[0]) - t0).rem_euclid(TAU)
                })
                .collect();
            (rl.n_theta, t0, radii, angles)
        });
    let ring_cell = |p: Vec2| {
        rings.as_ref().map(|(nt, t0, radii, angles)| {
            let j = radii.partition_point(|&r| r <= p.norm());
            let t = (p[1].atan2(p[0]) - t0).rem_euclid(TAU);
            j * nt + angles.partition_point(|&a| a <= t)
        })
    };
    let inside = |r: &(f64, f64)| r.0.abs() <= 1.0 + 1e-12 && r.1.abs() <= 1.0 + 1e-12;
    let try_cell = |c: usize, p: Vec2| {
        (c < mesh.n_cells())
            .then(|| inverse_map(mesh, c, p))
            .flatten()
            .filter(inside)
            .map(|(xi, eta)| (c, xi, eta))
    };
    let mut hint: Option<usize> = None;
    points
        .iter()
        .map(|&p| {
            let found = ring_cell(p)
                .and_then(|c| try_cell(c, p))
                .or_else(|| hint.and_then(|c| try_cell(c, p)))
                .unwrap_or_else(|| {
                    loc.get_or_init(|| PointLocator::new(mesh))
                        .locate_nearest(mesh, p)
                });
            hint = Some(found.0);
            found
        })
        .collect()
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

    /// `locate_points` on graded ring meshes (Q1 and Q2, uniform and graded in θ, a rotated
    /// first ray) finds what `locate_nearest` finds: for the nodes of a finer mesh of the same
    /// annulus (not nested in the coarser one where graded), points off the nodes, and points
    /// on the exact outer circle, just outside the Q2 arcs. A point inside a cell maps back to
    /// itself; the cell may differ only for a point on a shared edge.
    #[test]
    fn locate_points_agrees_with_the_bucket_search() {
        let mut seed = 7u64;
        let mut rnd = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for (degree, gr, gt) in [(2, 1.0, 0.0), (2, 1.7, 0.0), (1, 1.3, 0.4), (2, 0.6, 0.3)] {
            let spec = |n_r: usize, n_theta: usize| AnnulusSpec {
                ri: 1.0,
                ro: 2.0,
                n_r,
                n_theta,
                degree,
                grading_r: gr,
                grading_theta: gt,
            };
            let mut coarse = annulus(&spec(3, 20));
            coarse.make_isoparametric();
            let rot =
                crate::math::Mat2::new(0.6f64.cos(), -0.6f64.sin(), 0.6f64.sin(), 0.6f64.cos());
            for x in coarse.nodes.iter_mut() {
                *x = rot * *x;
            }
            let fine = annulus(&spec(7, 44));
            let mut points: Vec<Vec2> = fine.nodes.iter().map(|x| rot * x).collect();
            for _ in 0..500 {
                let (r, t) = (1.0 + rnd(), std::f64::consts::TAU * rnd());
                points.push(Vec2::new(r * t.cos(), r * t.sin()));
            }
            for _ in 0..50 {
                let t = std::f64::consts::TAU * rnd();
                points.push(Vec2::new(2.0 * t.cos(), 2.0 * t.sin()));
            }
            let loc = PointLocator::new(&coarse);
            let found = locate_points(&coarse, &points);
            let mut n = [0.0; 9];
            let at = |c: usize, xi: f64, eta: f64, n: &mut [f64; 9]| -> Vec2 {
                shape_values(&coarse, c, xi, eta, n);
                coarse
                    .cell_nodes(c)
                    .iter()
                    .enumerate()
                    .map(|(a, &k)| coarse.nodes[k as usize] * n[a])
                    .sum()
            };
            for (p, &(c, xi, eta)) in points.iter().zip(&found) {
                let (c0, xi0, eta0) = loc.locate_nearest(&coarse, *p);
                let (q, q0) = (at(c, xi, eta, &mut n), at(c0, xi0, eta0, &mut n));
                assert!(
                    (q - q0).norm() <= 1e-10,
                    "degree {degree}, grading {gr}/{gt}: {p:?} -> cell {c} ({xi}, {eta}) at {q:?}, the search: cell {c0} ({xi0}, {eta0}) at {q0:?}"
                );
                if xi.abs() < 1.0 - 1e-9 && eta.abs() < 1.0 - 1e-9 {
                    assert_eq!(c, c0, "{p:?}");
                    assert!((q - p).norm() <= 1e-10, "{p:?} maps back to {q:?}");
                }
            }
        }
    }
}
