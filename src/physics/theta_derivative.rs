//! Nodal θ-derivatives on any mesh of the annulus, for the velocities of the steady mode's
//! strain-rate damping, v = ω ∂θχ = ω (t + ∂θu), t = (−X2, X1).
//!
//! The steady mode builds the conforming velocity field v_h = Σ_a N_a v_a from nodal values,
//! as the transient mode does with its nodal velocities, with
//! (∂θu)_a ≈ Σ_b w_ab u_b from one of two sources:
//!
//! - **rings** (a ring-structured mesh, [`RingDerivative`]): five-point Lagrange differences
//!   along the node's ring, fourth order;
//! - **cell average** (any mesh): the mean over the cells around node a of the cell's own
//!   derivative at X_a, ∇N_b(X_a) · t_a ([`SolidModel::cell_theta_derivative`]); second order
//!   on smooth meshes, and available on unstructured, footprint-refined or imported meshes.
//!
//! Either way node a's velocity depends on nodes beyond the cells around it, so the exact
//! tangent of the damping couples a cell with its neighbours' neighbours. The steady system
//! keeps the cells' own sparsity in its assembled matrix (each cell linearises with its own
//! derivative) and applies the difference to the exact tangent matrix-free
//! ([`crate::model::SolidSystem`]).
//!
//! Why not each cell's own derivative for the velocities themselves (v_h on cell c from
//! ∂θu_h of c alone), which would make that tangent exact with the undamped sparsity: on a
//! prescribed smooth state its damping residual converges at second order, against fourth
//! for both nodal sources (`tests/steady_damping.rs`); and on the rolling cylinder (Q2,
//! 8 × 128 to 32 × 512, frictionless, no contact damping) its loads converge to other values,
//! F_y −93.58 against −93.78 and the torque 4.48 against 4.45, the gap unchanged with a ten
//! times softer penalty, while the transient mode (nodal velocities ∂u/∂t) gives F_y −93.82
//! and −93.80 on 8 × 128 and 16 × 256. Without contact, under a body force concentrated near
//! the outer surface, the steady solve's torque with the cells' own derivatives drifts under
//! refinement (0.4517, 0.4548, 0.4556 on 4 × 64 … 16 × 256) where the nodal one has converged
//! (0.4522, 0.4526, 0.4526): the defect is in the solve, not in the contact. The nodal
//! velocities, continuous across cells, stay.

use super::ring_derivative::RingDerivative;
use super::solid::SolidModel;
use crate::math::Vec2;
use crate::mesh::Mesh;

/// Where the nodal derivative weights come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ThetaDerivativeSource {
    /// Five-point differences along the node rings.
    Rings,
    /// Mean of the cells' own derivatives at the node.
    CellAverage,
}

/// (∂θf)_a ≈ Σ_k w[k] f(idx[k]), k in ptr[a]..ptr[a + 1], for every node a.
#[derive(Clone, Debug)]
pub struct NodalThetaDerivative {
    pub ptr: Vec<usize>,
    pub idx: Vec<u32>,
    pub w: Vec<f64>,
    pub source: ThetaDerivativeSource,
}

impl NodalThetaDerivative {
    /// Ring differences where the mesh has rings long enough for the stencil, otherwise the
    /// cell average. `None` if a cell map is degenerate at one of its nodes.
    pub fn new(model: &SolidModel) -> Option<Self> {
        match RingDerivative::new(&model.mesh) {
            Some(r) => Some(Self::from_rings(&r)),
            None => Self::cell_average(model),
        }
    }

    pub fn from_rings(r: &RingDerivative) -> Self {
        let mut ptr = Vec::with_capacity(r.stencils.len() + 1);
        ptr.push(0);
        let (mut idx, mut w) = (Vec::new(), Vec::new());
        for st in &r.stencils {
            for &(b, wb) in st {
                idx.push(b);
                w.push(wb);
            }
            ptr.push(idx.len());
        }
        Self {
            ptr,
            idx,
            w,
            source: ThetaDerivativeSource::Rings,
        }
    }

    /// The mean over the cells containing each node of the cells' own derivatives there.
    pub fn cell_average(model: &SolidModel) -> Option<Self> {
        let mesh = &model.mesh;
        let n = mesh.n_nodes();
        // Per node: (neighbour, summed weight) and the number of cells.
        let mut rows: Vec<Vec<(u32, f64)>> = vec![Vec::new(); n];
        let mut count = vec![0usize; n];
        for c in 0..mesh.n_cells() {
            let d = model.cell_theta_derivative(c)?;
            let nodes = mesh.cell_nodes(c);
            let nn = nodes.len();
            for (m, &a) in nodes.iter().enumerate() {
                count[a as usize] += 1;
                let row = &mut rows[a as usize];
                for (b, &nb) in nodes.iter().enumerate() {
                    let wb = d[m * nn + b];
                    match row.iter_mut().find(|(k, _)| *k == nb) {
                        Some(e) => e.1 += wb,
                        None => row.push((nb, wb)),
                    }
                }
            }
        }
        let mut ptr = Vec::with_capacity(n + 1);
        ptr.push(0);
        let (mut idx, mut w) = (Vec::new(), Vec::new());
        for (row, &k) in rows.iter_mut().zip(&count) {
            row.sort_by_key(|e| e.0);
            for &(b, wb) in row.iter() {
                idx.push(b);
                w.push(wb / k.max(1) as f64);
            }
            ptr.push(idx.len());
        }
        Some(Self {
            ptr,
            idx,
            w,
            source: ThetaDerivativeSource::CellAverage,
        })
    }

    /// Three-point differences along the node rings (second order; the weights use the actual
    /// node angles): the preconditioner's stand-in for the five-point ring differences. Its
    /// stencil reaches one node passage beyond a node instead of two, and on a uniform ring its
    /// symbol is within a factor 1–5/3 of theirs at every wave number (both vanish at the grid
    /// scale). `None` without rings.
    pub fn three_point(mesh: &Mesh) -> Option<Self> {
        let r = RingDerivative::new(mesh)?;
        let two_pi = 2.0 * std::f64::consts::PI;
        let angles: Vec<f64> = mesh.nodes.iter().map(|x| x[1].atan2(x[0])).collect();
        let angle = |n: u32| angles[n as usize];
        let mut ptr = Vec::with_capacity(r.stencils.len() + 1);
        ptr.push(0);
        let (mut idx, mut w) = (Vec::new(), Vec::new());
        for st in &r.stencils {
            let h = super::ring_derivative::HALF;
            let (prev, centre, next) = (st[h - 1].0, st[h].0, st[h + 1].0);
            let unwrap = |d: f64| d - two_pi * (d / two_pi).round();
            let h1 = unwrap(angle(centre) - angle(prev));
            let h2 = unwrap(angle(next) - angle(centre));
            idx.extend_from_slice(&[prev, centre, next]);
            w.extend_from_slice(&[
                -h2 / (h1 * (h1 + h2)),
                (h2 - h1) / (h1 * h2),
                h1 / (h2 * (h1 + h2)),
            ]);
            ptr.push(idx.len());
        }
        Some(Self {
            ptr,
            idx,
            w,
            source: ThetaDerivativeSource::Rings,
        })
    }

    /// Nodal velocities v_a = ω (t_a + (∂θu)_a) into `out` (2 per node; `u` holds the nodal
    /// displacements in its first 2 · n_nodes entries).
    pub fn velocities(&self, mesh: &Mesh, u: &[f64], omega: f64, out: &mut [f64]) {
        for a in 0..self.ptr.len() - 1 {
            let x = mesh.nodes[a];
            let mut d = Vec2::new(-x[1], x[0]);
            for k in self.ptr[a]..self.ptr[a + 1] {
                let b = self.idx[k] as usize;
                d += Vec2::new(u[2 * b], u[2 * b + 1]) * self.w[k];
            }
            out[2 * a] = omega * d[0];
            out[2 * a + 1] = omega * d[1];
        }
    }

    /// out_a = ω (∂θ du)_a (2 per node), the linear part of [`Self::velocities`].
    pub fn apply(&self, du: &[f64], omega: f64, out: &mut [f64]) {
        for a in 0..self.ptr.len() - 1 {
            let (mut s0, mut s1) = (0.0, 0.0);
            for k in self.ptr[a]..self.ptr[a + 1] {
                let b = self.idx[k] as usize;
                s0 += du[2 * b] * self.w[k];
                s1 += du[2 * b + 1] * self.w[k];
            }
            out[2 * a] = omega * s0;
            out[2 * a + 1] = omega * s1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{Material, NeoHookean};
    use crate::mesh::{annulus, AnnulusSpec};
    use crate::physics::PressureMode;

    fn model(n_theta: usize, degree: usize, iso: bool) -> SolidModel {
        let mut m = annulus(&AnnulusSpec {
            ri: 1.0,
            ro: 2.0,
            n_r: 2,
            n_theta,
            degree,
            grading_r: 1.0,
            grading_theta: 0.3,
        });
        if iso {
            m.make_isoparametric();
        }
        let mat: Material = NeoHookean::new(1.0, 10.0).into();
        SolidModel::new(m, mat, 1.0, PressureMode::None)
    }

    fn max_error(d: &NodalThetaDerivative, mesh: &Mesh) -> f64 {
        let mut u = vec![0.0; 2 * mesh.n_nodes()];
        for (a, x) in mesh.nodes.iter().enumerate() {
            let (r, th) = (x.norm(), x[1].atan2(x[0]));
            u[2 * a] = r * (3.0 * th).sin();
            u[2 * a + 1] = (2.0 * th).cos() / r;
        }
        let mut v = vec![0.0; u.len()];
        d.apply(&u, 1.0, &mut v);
        let mut e = 0.0f64;
        for (a, x) in mesh.nodes.iter().enumerate() {
            let (r, th) = (x.norm(), x[1].atan2(x[0]));
            let ex = [3.0 * r * (3.0 * th).cos(), -2.0 * (2.0 * th).sin() / r];
            e = e
                .max((v[2 * a] - ex[0]).abs())
                .max((v[2 * a + 1] - ex[1]).abs());
        }
        e
    }

    /// The cell-average derivative converges at (at least) second order for Q1 and Q2, on
    /// polar and isoparametric cells of a graded annulus; the cell derivative is exact for a
    /// field the element reproduces.
    #[test]
    fn cell_average_converges() {
        for (degree, iso, min_rate) in [(1, false, 1.8), (2, false, 1.9), (2, true, 1.9)] {
            let errs: Vec<f64> = [24usize, 48, 96]
                .iter()
                .map(|&n| {
                    let m = model(n, degree, iso);
                    let d = NodalThetaDerivative::cell_average(&m).unwrap();
                    assert_eq!(d.source, ThetaDerivativeSource::CellAverage);
                    max_error(&d, &m.mesh)
                })
                .collect();
            let rate = (errs[1] / errs[2]).log2();
            println!("degree {degree}, isoparametric {iso}: errors {errs:?}, rate {rate:.2}");
            assert!(rate > min_rate, "degree {degree} iso {iso}: {errs:?}");
        }
        // ∂θ of the linear field u = X (exact for every element): (−X2, X1).
        let m = model(12, 2, true);
        let d = NodalThetaDerivative::cell_average(&m).unwrap();
        let u: Vec<f64> = m.mesh.nodes.iter().flat_map(|x| [x[0], x[1]]).collect();
        let mut v = vec![0.0; u.len()];
        d.apply(&u, 1.0, &mut v);
        for (a, x) in m.mesh.nodes.iter().enumerate() {
            assert!((v[2 * a] + x[1]).abs() < 1e-12 && (v[2 * a + 1] - x[0]).abs() < 1e-12);
        }
    }

    /// On a ring mesh the default is the ring differences, which agree with the ring
    /// operator itself.
    #[test]
    fn rings_are_preferred_where_present() {
        let m = model(24, 2, false);
        let d = NodalThetaDerivative::new(&m).unwrap();
        assert_eq!(d.source, ThetaDerivativeSource::Rings);
        let r = RingDerivative::new(&m.mesh).unwrap();
        let u: Vec<f64> = (0..2 * m.mesh.n_nodes())
            .map(|i| (0.37 * i as f64).sin())
            .collect();
        let (mut a, mut b) = (vec![0.0; u.len()], vec![0.0; u.len()]);
        d.velocities(&m.mesh, &u, 1.5, &mut a);
        r.velocities(&m.mesh, &u, 1.5, &mut b);
        assert_eq!(a, b);
    }
}
