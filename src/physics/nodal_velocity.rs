//! Continuous nodal velocities of the steady (θ-referential) mode, on any mesh of the annulus.
//!
//! In steady rolling the material velocity is v = ω ∂θχ with ∂θ = t · ∇, t = (−X2, X1) the
//! derivative along the reference circles (DESIGN §5). The elementwise ∂θχ_h of a C⁰ field is
//! discontinuous at the cell edges: used directly, it gave a ±μp oscillation of the friction
//! traction in the stick zone (a node shared by two facets sees two slip velocities) and a
//! strain-rate damping ∇(ω ∂θχ_h) (second derivatives without jump terms) that converged to
//! another solution. The velocity used by every velocity-dependent steady term (strain-rate
//! damping, normal damping δ̇ = −v2, friction slip w = v1 − v0) is therefore the continuous
//! interpolant v_h = Σ_a N_a v_a of nodal velocities
//!
//! ```text
//! v_a = ω (t_a + (∂θu)_a),   (∂θu)_a = Σ_e ∫_e N_a ∂θu_h dV / Σ_e ∫_e N_a dV
//! ```
//!
//! the lumped-L2 projection of ∂θu_h onto the nodes (t_a = (−X2_a, X1_a) is exact: a rigid
//! rotation χ = X has v_a = ω t_a and no strain rate). It needs no ring structure. For Q2
//! Lagrange cells the lumped weights ∫ N_a are positive and the projection reproduces fields
//! linear on an affine cell exactly (Simpson's rule has exact first moments), so the nodal
//! velocities are second-order accurate, boundary nodes included.
//!
//! The projection is linear: (∂θu)_a = Σ_b P_ab u_b (per component), with P_ab non-zero only
//! for nodes b of the cells around a. A term that depends on v_a therefore couples a cell with
//! the nodes of its neighbours (a 3 × 3-cell patch instead of one cell). Assembling that
//! exactly doubles the matrix's reach and multiplies the LU fill. The steady system assembles
//! instead, per cell, the *cell-local* projection P^e_ab = ∫_e N_a ∂θN_b / ∫_e N_a (the same
//! construction restricted to the cell: it keeps the element pattern, annihilates constants and
//! reproduces linear fields), and supplies the remainder of the exact Jacobian as an operator
//! (see [`crate::driver::SolidSystem`]), with which Newton corrects its step. The contact terms,
//! whose slip derivative is large for a small friction regularisation, use the exact P on the
//! few boundary cells around each facet.

use super::solid::SolidModel;
use crate::element::{ShapeTable, Q1, Q2};
use crate::math::Vec2;

/// The lumped-L2 projection of ∂θ onto the nodes and its cell-local counterparts.
#[derive(Clone, Debug)]
pub struct ThetaProjection {
    /// CSR rows over the nodes: (∂θu)_a ≈ Σ_{k in row a} weights[k] u(cols[k]).
    pub row_ptr: Vec<usize>,
    pub cols: Vec<u32>,
    pub weights: Vec<f64>,
    /// Per cell (offset `local_offsets[c]`), the row-major N × N cell-local projection
    /// P^e_ab = ∫_e N_a ∂θN_b / ∫_e N_a over the cell's local nodes.
    pub local: Vec<f64>,
    pub local_offsets: Vec<usize>,
}

impl ThetaProjection {
    /// Build the projection of `model`'s mesh (Gauss quadrature of order p + 2 per direction).
    pub fn new(model: &SolidModel) -> Self {
        let mesh = &model.mesh;
        let n_nodes = mesh.n_nodes();
        let q1 = ShapeTable::gauss::<Q1>(3);
        let q2 = ShapeTable::gauss::<Q2>(4);
        let mut mass = vec![0.0; n_nodes];
        // Per cell: N × N matrix B^e_ab = ∫_e N_a ∂θN_b and lumped masses m^e_a.
        let mut local = Vec::new();
        let mut local_offsets = vec![0];
        let mut cell_b: Vec<f64> = Vec::new();
        let mut cell_b_off = vec![0];
        for c in 0..mesh.n_cells() {
            let nodes = mesh.cell_nodes(c);
            let n = nodes.len();
            let mut b = vec![0.0; n * n];
            let mut m = vec![0.0; n];
            match n {
                4 => model.theta_moments::<4>(c, &q1, &mut b, &mut m),
                _ => model.theta_moments::<9>(c, &q2, &mut b, &mut m),
            }
            for (a, &na) in nodes.iter().enumerate() {
                mass[na as usize] += m[a];
                for j in 0..n {
                    local.push(if m[a] != 0.0 {
                        b[a * n + j] / m[a]
                    } else {
                        0.0
                    });
                }
            }
            local_offsets.push(local.len());
            cell_b.extend_from_slice(&b);
            cell_b_off.push(cell_b.len());
        }
        // Global rows: gather (b, value) pairs per node, then merge duplicates.
        let mut rows: Vec<Vec<(u32, f64)>> = vec![Vec::new(); n_nodes];
        for c in 0..mesh.n_cells() {
            let nodes = mesh.cell_nodes(c);
            let n = nodes.len();
            let b = &cell_b[cell_b_off[c]..cell_b_off[c + 1]];
            for (a, &na) in nodes.iter().enumerate() {
                for (j, &nb) in nodes.iter().enumerate() {
                    rows[na as usize].push((nb, b[a * n + j]));
                }
            }
        }
        let mut row_ptr = vec![0];
        let (mut cols, mut weights) = (Vec::new(), Vec::new());
        for (a, row) in rows.iter_mut().enumerate() {
            row.sort_unstable_by_key(|e| e.0);
            let inv = if mass[a] != 0.0 { 1.0 / mass[a] } else { 0.0 };
            let mut k = 0;
            while k < row.len() {
                let col = row[k].0;
                let mut s = 0.0;
                while k < row.len() && row[k].0 == col {
                    s += row[k].1;
                    k += 1;
                }
                cols.push(col);
                weights.push(s * inv);
            }
            row_ptr.push(cols.len());
        }
        Self {
            row_ptr,
            cols,
            weights,
            local,
            local_offsets,
        }
    }

    /// Row of node `a`: (nodes, weights).
    #[inline]
    pub fn row(&self, a: usize) -> (&[u32], &[f64]) {
        let r = self.row_ptr[a]..self.row_ptr[a + 1];
        (&self.cols[r.clone()], &self.weights[r])
    }

    /// Cell-local projection of cell `c` (row-major N × N).
    #[inline]
    pub fn cell_local(&self, c: usize) -> &[f64] {
        &self.local[self.local_offsets[c]..self.local_offsets[c + 1]]
    }

    /// Nodal velocities v_a = ω (t_a + Σ_b P_ab u_b) into `out` (2 per node; `u` holds the
    /// nodal displacements in its first 2 · n_nodes entries).
    pub fn velocities(&self, nodes: &[Vec2], u: &[f64], omega: f64, out: &mut [f64]) {
        for (a, x) in nodes.iter().enumerate() {
            let (cols, w) = self.row(a);
            let mut d = Vec2::new(-x[1], x[0]);
            for (&b, &wb) in cols.iter().zip(w) {
                let b = b as usize;
                d[0] += wb * u[2 * b];
                d[1] += wb * u[2 * b + 1];
            }
            out[2 * a] = omega * d[0];
            out[2 * a + 1] = omega * d[1];
        }
    }

    /// The linear part alone: out_a = ω Σ_b P_ab du_b (2 per node).
    pub fn apply(&self, du: &[f64], omega: f64, out: &mut [f64]) {
        for a in 0..self.row_ptr.len() - 1 {
            let (cols, w) = self.row(a);
            let (mut s0, mut s1) = (0.0, 0.0);
            for (&b, &wb) in cols.iter().zip(w) {
                let b = b as usize;
                s0 += wb * du[2 * b];
                s1 += wb * du[2 * b + 1];
            }
            out[2 * a] = omega * s0;
            out[2 * a + 1] = omega * s1;
        }
    }

    /// Bytes held (for memory reports).
    pub fn bytes(&self) -> usize {
        8 * (self.row_ptr.len() + self.weights.len() + self.local.len() + self.local_offsets.len())
            + 4 * self.cols.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{Material, MooneyRivlin};
    use crate::mesh::{annulus, AnnulusSpec};
    use crate::physics::PressureMode;

    fn model(n_theta: usize, degree: usize, grading_theta: f64) -> SolidModel {
        let mesh = annulus(&AnnulusSpec {
            ri: 1.0,
            ro: 2.0,
            n_r: 3,
            n_theta,
            degree,
            grading_r: 1.5,
            grading_theta,
        });
        let mat: Material = MooneyRivlin::new(80.0, 20.0, 4000.0).into();
        SolidModel::new(mesh, mat, 1.0, PressureMode::None)
    }

    /// Nodal ∂θ of a smooth field: second order on uniform and graded Q2 meshes (boundary
    /// nodes included), exact zero for a constant, exact velocity ω t for no displacement.
    #[test]
    fn projected_theta_derivative_is_second_order() {
        for g in [0.0, 0.3] {
            let mut errs = Vec::new();
            for n in [24usize, 48, 96] {
                let m = model(n, 2, g);
                let p = ThetaProjection::new(&m);
                let nodes = &m.mesh.nodes;
                // u = (sin 3θ r², cos 2θ r): ∂θu = (3 cos 3θ r², −2 sin 2θ r).
                let mut u = vec![0.0; 2 * nodes.len()];
                for (a, x) in nodes.iter().enumerate() {
                    let (r, th) = (x.norm(), x[1].atan2(x[0]));
                    u[2 * a] = (3.0 * th).sin() * r * r;
                    u[2 * a + 1] = (2.0 * th).cos() * r;
                }
                let mut v = vec![0.0; u.len()];
                p.apply(&u, 1.0, &mut v);
                let mut e = 0.0f64;
                for (a, x) in nodes.iter().enumerate() {
                    let (r, th) = (x.norm(), x[1].atan2(x[0]));
                    let ex = [3.0 * (3.0 * th).cos() * r * r, -2.0 * (2.0 * th).sin() * r];
                    e = e
                        .max((v[2 * a] - ex[0]).abs())
                        .max((v[2 * a + 1] - ex[1]).abs());
                }
                errs.push(e);
            }
            // The radial mesh is fixed (3 cells), so the error tends to a radial floor;
            // the first halving must show second order.
            let rate = (errs[0] / errs[1]).log2();
            assert!(rate > 1.8, "grading {g}: errors {errs:?}, rate {rate}");
            // Constants have zero derivative; u = 0 gives the rigid velocity exactly.
            let m = model(24, 2, g);
            let p = ThetaProjection::new(&m);
            let nn = m.mesh.n_nodes();
            let mut u = vec![0.0; 2 * nn];
            for a in 0..nn {
                u[2 * a] = 0.3;
                u[2 * a + 1] = -1.1;
            }
            let mut v = vec![1.0; 2 * nn];
            p.apply(&u, 2.0, &mut v);
            assert!(v.iter().all(|x| x.abs() < 1e-12), "constant field");
            let zero = vec![0.0; 2 * nn];
            p.velocities(&m.mesh.nodes, &zero, 2.0, &mut v);
            for (a, x) in m.mesh.nodes.iter().enumerate() {
                assert!((v[2 * a] + 2.0 * x[1]).abs() < 1e-14);
                assert!((v[2 * a + 1] - 2.0 * x[0]).abs() < 1e-14);
            }
        }
    }

    /// The cell-local projection annihilates constants and reproduces linear fields
    /// (Q2, in the interior of the element's span) at the cell's nodes.
    #[test]
    fn cell_local_projection_is_consistent() {
        let m = model(16, 2, 0.0);
        let p = ThetaProjection::new(&m);
        for c in 0..m.mesh.n_cells() {
            let nodes = m.mesh.cell_nodes(c);
            let n = nodes.len();
            let l = p.cell_local(c);
            for a in 0..n {
                let s: f64 = l[a * n..(a + 1) * n].iter().sum();
                assert!(s.abs() < 1e-10, "cell {c} row {a}: {s}");
                // u = X1: ∂θu = t1 = −X2 (polar cells represent X only approximately: loose).
                let d: f64 = (0..n)
                    .map(|b| l[a * n + b] * m.mesh.nodes[nodes[b] as usize][0])
                    .sum();
                let ex = -m.mesh.nodes[nodes[a] as usize][1];
                assert!((d - ex).abs() < 2e-2, "cell {c} node {a}: {d} vs {ex}");
            }
        }
    }
}
