//! Nodal θ-derivatives along the node rings of a ring-structured (annulus) mesh, for the
//! strain-rate damping of the steady (θ-referential) mode.
//!
//! In steady rolling the material velocity is v = ω ∂θχ. The transient mode's damping acts on
//! Ė = sym(Fᵀ ∇v_h) with v_h the interpolant of the *nodal* velocities, a continuous field. The
//! steady mode used to take ∇(ω ∂θχ_h) elementwise instead: ∂θχ_h is discontinuous across the
//! radial cell edges, and that broken gradient (second derivatives of the Q2 interpolant
//! without jump terms) gives a steady operator whose solutions do not converge to the
//! transient's: at 20 rad/s on the paper's cylinder the two modes stayed 1.7 % apart in the
//! field and ~1 % in the hub force however fine the circumferential mesh (see
//! `tests/compare.rs`). The steady mode now builds the same conforming velocity field as the
//! transient one: nodal velocities v_a = ω (t_a + (∂θu)_a), t_a = (−X2, X1) exact, with
//! (∂θu)_a from a five-point Lagrange difference along the node's ring (fourth order on a
//! uniform ring; the weights use the actual node angles, so graded rings are handled too).

use crate::math::Vec2;
use crate::mesh::Mesh;

/// Half-width of the difference stencil (5 points).
pub const HALF: usize = 2;
/// Points per stencil.
pub const WIDTH: usize = 2 * HALF + 1;

/// Five-point ring-difference weights of every node.
#[derive(Clone, Debug)]
pub struct RingDerivative {
    /// Nodes per ring.
    pub per_ring: usize,
    /// Per node: the stencil nodes (positions l − 2 … l + 2 on the node's ring) and weights,
    /// (∂θf)_a ≈ Σ_k w_k f(node_k).
    pub stencils: Vec<[(u32, f64); WIDTH]>,
}

/// Derivative at `t0` of the Lagrange interpolant through (t_k, ·), as weights:
/// L_j'(t0) = Σ_{m≠j} Π_{k≠j,m} (t0 − t_k) / Π_{k≠j} (t_j − t_k), one division per point.
pub fn lagrange_derivative_weights(t: &[f64; WIDTH], t0: f64) -> [f64; WIDTH] {
    let mut w = [0.0; WIDTH];
    for j in 0..WIDTH {
        let mut den = 1.0;
        let mut num = 0.0;
        for m in 0..WIDTH {
            if m == j {
                continue;
            }
            den *= t[j] - t[m];
            num += t
                .iter()
                .enumerate()
                .filter(|&(k, _)| k != j && k != m)
                .map(|(_, &tk)| t0 - tk)
                .product::<f64>();
        }
        w[j] = num / den;
    }
    w
}

impl RingDerivative {
    /// `None` if the mesh has no ring structure or its rings are too short for the stencil.
    pub fn new(mesh: &Mesh) -> Option<Self> {
        let rl = mesh.rings?;
        let per = rl.per_ring;
        if per < WIDTH + 1 {
            return None;
        }
        let two_pi = 2.0 * std::f64::consts::PI;
        let angles: Vec<f64> = mesh.nodes.iter().map(|x| x[1].atan2(x[0])).collect();
        let angle = |n: u32| angles[n as usize];
        let mut stencils = Vec::with_capacity(mesh.n_nodes());
        for m in 0..rl.rings {
            for l in 0..per {
                let node =
                    |o: i64| (m * per + (l as i64 + o).rem_euclid(per as i64) as usize) as u32;
                let t0 = angle(node(0));
                let mut t = [0.0; WIDTH];
                let mut nodes = [0u32; WIDTH];
                for (k, o) in (-(HALF as i64)..=HALF as i64).enumerate() {
                    nodes[k] = node(o);
                    // Unwrapped angle relative to the centre node.
                    let mut d = angle(nodes[k]) - t0;
                    d -= two_pi * (d / two_pi).round();
                    t[k] = d;
                }
                let w = lagrange_derivative_weights(&t, 0.0);
                let mut s = [(0u32, 0.0); WIDTH];
                for k in 0..WIDTH {
                    s[k] = (nodes[k], w[k]);
                }
                stencils.push(s);
            }
        }
        Some(Self {
            per_ring: per,
            stencils,
        })
    }

    /// Nodal velocities v_a = ω (t_a + (∂θu)_a) into `out` (2 per node; `u` holds the nodal
    /// displacements in its first 2 · n_nodes entries).
    pub fn velocities(&self, mesh: &Mesh, u: &[f64], omega: f64, out: &mut [f64]) {
        for (a, st) in self.stencils.iter().enumerate() {
            let x = mesh.nodes[a];
            let mut d = Vec2::new(-x[1], x[0]);
            for &(b, w) in st {
                let b = b as usize;
                d += Vec2::new(u[2 * b], u[2 * b + 1]) * w;
            }
            out[2 * a] = omega * d[0];
            out[2 * a + 1] = omega * d[1];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{annulus, AnnulusSpec};

    fn mesh(grading_theta: f64) -> Mesh {
        annulus(&AnnulusSpec {
            ri: 1.0,
            ro: 2.0,
            n_r: 2,
            n_theta: 24,
            degree: 2,
            grading_r: 1.0,
            grading_theta,
        })
    }

    /// Weights differentiate quartics exactly and a smooth periodic field to fourth order,
    /// on uniform and graded rings.
    #[test]
    fn ring_differences_are_fourth_order() {
        for g in [0.0, 0.3] {
            let mut errs = Vec::new();
            for n in [24usize, 48] {
                let m = annulus(&AnnulusSpec {
                    ri: 1.0,
                    ro: 2.0,
                    n_r: 1,
                    n_theta: n,
                    degree: 2,
                    grading_r: 1.0,
                    grading_theta: g,
                });
                let rd = RingDerivative::new(&m).unwrap();
                let mut u = vec![0.0; 2 * m.n_nodes()];
                for (a, x) in m.nodes.iter().enumerate() {
                    let th = x[1].atan2(x[0]);
                    u[2 * a] = (3.0 * th).sin();
                    u[2 * a + 1] = (2.0 * th).cos();
                }
                let mut v = vec![0.0; u.len()];
                rd.velocities(&m, &u, 1.0, &mut v);
                let mut e = 0.0f64;
                for (a, x) in m.nodes.iter().enumerate() {
                    let th = x[1].atan2(x[0]);
                    let ex = [
                        -x[1] + 3.0 * (3.0 * th).cos(),
                        x[0] - 2.0 * (2.0 * th).sin(),
                    ];
                    e = e
                        .max((v[2 * a] - ex[0]).abs())
                        .max((v[2 * a + 1] - ex[1]).abs());
                }
                errs.push(e);
            }
            let rate = (errs[0] / errs[1]).log2();
            assert!(rate > 3.7, "grading {g}: errors {errs:?}, rate {rate}");
        }
        // Rigid rotation: exact velocity ω t.
        let m = mesh(0.0);
        let rd = RingDerivative::new(&m).unwrap();
        let u = vec![0.0; 2 * m.n_nodes()];
        let mut v = vec![0.0; u.len()];
        rd.velocities(&m, &u, 2.0, &mut v);
        for (a, x) in m.nodes.iter().enumerate() {
            assert!((v[2 * a] + 2.0 * x[1]).abs() < 1e-14);
            assert!((v[2 * a + 1] - 2.0 * x[0]).abs() < 1e-14);
        }
    }
}
