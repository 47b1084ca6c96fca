//! Continuous friction slip of the three-dimensional steady (θ-referential) mode: nodal
//! θ-derivatives along the node rings of the contact surface.
//!
//! In steady rolling the material velocity at the referential position X is v = ω ∂θχ, and
//! the friction slip against the road is w = (v1 − V1, v3 − V3). Taking ∂θu_h facet by facet
//! (∂_d N_b u_b, [`super::facet3d`]) gives a slip that jumps at the facet edges across which θ
//! advances: inside the stick zone, where the exact slip is below the regularisation ε, the two
//! one-sided values at a shared node differ by more than ε, the regularised traction saws
//! between +μ t_n and −μ t_n within every facet, and Newton's basin shrinks to nothing as ε
//! decreases (a wheel of Hex27 cells at a 2° slip angle stalls at ε = 1 % of the rolling speed).
//! The plane program has the same defect and the same cure ([`super::steady_slip`]), which this
//! module carries over to the revolved surface.
//!
//! The contact facets' nodes are grouped into rings: nodes with the same reference radius
//! |(X1, X2)| and axial position X3 (to 1e-9 of the largest radius), sorted by the polar angle
//! θ = atan2(X2, X1). A ring is closed when every two angle-consecutive nodes share a facet,
//! else it is split into arcs. On each ring the nodal derivative is the derivative at θ_a of the
//! Lagrange polynomial through five consecutive nodes,
//!
//! ```text
//! (∂θu)_a = Σ_k W_ak u_k,   W_ak = L_k'(θ_a)   (k: ring neighbours a−2 … a+2),
//! ```
//!
//! fourth order on smooth fields whatever the spacing (periodic on a closed ring; on an open
//! arc the window is shifted inward at its ends). The friction velocity at a facet point is then
//!
//! ```text
//! v_w(η) = ω (d(η) + Σ_j N_j(η) (∂θu)_j)       (j: the facet's nodes)
//! ```
//!
//! with d the facet's own geometric ∂θX ([`super::facet3d`]), continuous across facets. A
//! facet's friction traction then depends on the displacements of its cell's nodes and of the
//! stencil nodes outside the cell (two beyond each θ-end of the facet, on each of its rings):
//! the contact element is the cell's nodes followed by those extra nodes, with the exact
//! tangent. The normal damping rate δ̇ = −v2 keeps the facet-wise derivative (its law is smooth
//! in δ̇: the jump at a node is a discretisation error, not a switch of the traction's sign).

use super::steady_slip::arc_weights;
use crate::element::hex::{face_nodes, Hex27, Hex8};
use crate::mesh::hex_mesh::{HexFacet, HexMesh};
use crate::physics::ring_derivative::WIDTH;
use std::collections::{HashMap, HashSet};

/// Most stencil nodes of a facet outside its cell (Hex27: 4 per ring × 3 rings).
pub const MAX_EXTRA: usize = 16;

/// Most nodes of a facet (Hex27: 3 × 3).
pub const MAX_FACET_NODES: usize = 9;

/// Per facet: the stencil nodes outside the cell, and the nodal-derivative weights of the
/// facet's nodes in the facet's extended local numbering (the cell's nodes 0..N, then the
/// extra nodes N..N + n_extra).
#[derive(Clone, Debug)]
pub struct SteadySlip3D {
    extra: Vec<u32>,
    off: Vec<usize>,
    /// Per facet, per facet node j (in [`face_nodes`] order): (extended local node, weight) of
    /// (∂θu)_j = Σ w u.
    stencil: Vec<[[(u8, f64); WIDTH]; MAX_FACET_NODES]>,
}

/// The reference nodes of facet `f` (global indices, in [`face_nodes`] order).
fn facet_node_list(mesh: &HexMesh, f: &HexFacet) -> Vec<u32> {
    let c = f.cell as usize;
    let cn = mesh.cell_nodes(c);
    let local = if mesh.degree[c] == 1 {
        face_nodes::<Hex8>(f.face as usize)
    } else {
        face_nodes::<Hex27>(f.face as usize)
    };
    local.iter().map(|&a| cn[a]).collect()
}

/// Five-point nodal θ-derivative weights of every node of the facets: node → (node, weight).
/// `None` when a ring or arc has fewer than five nodes or two nodes on one ray.
pub fn ring_weights(
    mesh: &HexMesh,
    facets: &[HexFacet],
) -> Option<HashMap<u32, [(u32, f64); WIDTH]>> {
    ring_weights_of(mesh, facets.iter().map(|f| facet_node_list(mesh, f)))
}

/// [`ring_weights`] of the nodes of `groups` (node lists, e.g. facets or cells): nodes of one
/// ring are angle-consecutive neighbours when some group holds both.
pub fn ring_weights_of(
    mesh: &HexMesh,
    groups: impl Iterator<Item = Vec<u32>>,
) -> Option<HashMap<u32, [(u32, f64); WIDTH]>> {
    let scale = mesh
        .nodes
        .iter()
        .map(|x| x[0].hypot(x[1]))
        .fold(0.0f64, f64::max)
        .max(f64::MIN_POSITIVE);
    let key = |n: u32| {
        let x = mesh.nodes[n as usize];
        (
            (x[0].hypot(x[1]) / scale * 1e9).round() as i64,
            (x[2] / scale * 1e9).round() as i64,
        )
    };
    let angle = |n: u32| {
        let x = mesh.nodes[n as usize];
        x[1].atan2(x[0])
    };
    let mut rings: HashMap<(i64, i64), Vec<u32>> = HashMap::new();
    let mut shared: HashSet<(u32, u32)> = HashSet::new();
    for nodes in groups {
        for (i, &a) in nodes.iter().enumerate() {
            for &b in &nodes[i + 1..] {
                if key(a) == key(b) {
                    shared.insert((a.min(b), a.max(b)));
                }
            }
        }
        for a in nodes {
            rings.entry(key(a)).or_default().push(a);
        }
    }
    let mut out = HashMap::new();
    for nodes in rings.values_mut() {
        nodes.sort_unstable();
        nodes.dedup();
        nodes.sort_by(|&a, &b| angle(a).total_cmp(&angle(b)));
        let n = nodes.len();
        if n < WIDTH {
            return None;
        }
        let linked = |a: u32, b: u32| shared.contains(&(a.min(b), a.max(b)));
        let breaks: Vec<usize> = (0..n)
            .filter(|&i| !linked(nodes[i], nodes[(i + 1) % n]))
            .collect();
        let closed = breaks.is_empty();
        let arcs: Vec<Vec<u32>> = if closed {
            vec![nodes.clone()]
        } else {
            (0..breaks.len())
                .map(|k| {
                    let (start, end) = ((breaks[k] + 1) % n, breaks[(k + 1) % breaks.len()]);
                    let len = (end + n - start) % n + 1;
                    (0..len).map(|i| nodes[(start + i) % n]).collect()
                })
                .collect()
        };
        for arc in &arcs {
            arc_weights(arc, closed, angle, &mut out)?;
        }
    }
    Some(out)
}

impl SteadySlip3D {
    /// `None` when the facets' nodes do not form rings or arcs of at least five nodes with
    /// distinct angles, or a facet would need more than [`MAX_EXTRA`] nodes outside its cell
    /// (the contact then keeps the facet-wise derivative).
    pub fn new(mesh: &HexMesh, facets: &[HexFacet]) -> Option<Self> {
        let weights = ring_weights(mesh, facets)?;
        let mut extra = Vec::new();
        let mut off = vec![0];
        let mut stencil = Vec::with_capacity(facets.len());
        for f in facets {
            let cn = mesh.cell_nodes(f.cell as usize);
            let mut mine: Vec<u32> = Vec::new();
            let mut st = [[(0u8, 0.0); WIDTH]; MAX_FACET_NODES];
            for (j, a) in facet_node_list(mesh, f).into_iter().enumerate() {
                for (k, &(b, w)) in weights.get(&a)?.iter().enumerate() {
                    let i = match cn.iter().position(|&c| c == b) {
                        Some(i) => i,
                        None => match mine.iter().position(|&e| e == b) {
                            Some(i) => cn.len() + i,
                            None => {
                                mine.push(b);
                                cn.len() + mine.len() - 1
                            }
                        },
                    };
                    st[j][k] = (i as u8, w);
                }
            }
            if mine.len() > MAX_EXTRA {
                return None;
            }
            extra.extend_from_slice(&mine);
            off.push(extra.len());
            stencil.push(st);
        }
        Some(Self {
            extra,
            off,
            stencil,
        })
    }

    /// The stencil nodes of facet `e` outside its cell (extended local nodes N, N + 1, …).
    pub fn extra(&self, e: usize) -> &[u32] {
        &self.extra[self.off[e]..self.off[e + 1]]
    }

    /// Weights of facet `e`: per facet node j, (extended local node, weight).
    pub fn stencil(&self, e: usize) -> &[[(u8, f64); WIDTH]; MAX_FACET_NODES] {
        &self.stencil[e]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::revolved::{revolved, RevolvedSpec};

    fn wheel(n_theta: usize, degree: usize, grading_theta: f64) -> HexMesh {
        revolved(&RevolvedSpec {
            ri: 1.0,
            ro: 2.0,
            width: 0.5,
            n_r: 1,
            n_z: 2,
            n_theta,
            degree,
            grading_r: 1.0,
            grading_theta,
            theta_ratio: 1.0,
            grading_z: 1.0,
            half_width: false,
            crown_radius: None,
        })
        .expect("mesh")
    }

    /// The nodal derivatives of f = sin 3θ · (1 + X3) on the outer surface converge at fourth
    /// order on uniform and graded rings, Hex8 and Hex27.
    #[test]
    fn ring_derivative_is_fourth_order() {
        for degree in [1usize, 2] {
            for g in [0.0, 0.5] {
                let mut errs = Vec::new();
                for n in [48usize, 96] {
                    let m = wheel(n, degree, g);
                    let w = ring_weights(&m, m.facet_set("outer")).expect("weights");
                    let f = |b: u32| {
                        let x = m.nodes[b as usize];
                        (3.0 * x[1].atan2(x[0])).sin() * (1.0 + x[2])
                    };
                    let mut e = 0.0f64;
                    for (&a, st) in &w {
                        let x = m.nodes[a as usize];
                        let d: f64 = st.iter().map(|&(b, wb)| wb * f(b)).sum();
                        let exact = 3.0 * (3.0 * x[1].atan2(x[0])).cos() * (1.0 + x[2]);
                        e = e.max((d - exact).abs());
                    }
                    errs.push(e);
                }
                let rate = (errs[0] / errs[1]).log2();
                assert!(
                    rate > 3.7,
                    "degree {degree}, grading {g}: errors {errs:?}, rate {rate}"
                );
            }
        }
    }

    /// Facet stencils: every weight refers to a cell node or a listed extra node of the same
    /// ring, and the extended list reproduces the ring weights.
    #[test]
    fn facet_stencils_reproduce_ring_weights() {
        for degree in [1usize, 2] {
            let m = wheel(16, degree, 0.0);
            let facets = m.facet_set("outer").to_vec();
            let s = SteadySlip3D::new(&m, &facets).expect("slip");
            let w = ring_weights(&m, &facets).expect("weights");
            for (e, f) in facets.iter().enumerate() {
                let cn = m.cell_nodes(f.cell as usize);
                let ext: Vec<u32> = cn.iter().chain(s.extra(e)).copied().collect();
                // Two beyond each θ-end on each of the facet's rings.
                assert_eq!(s.extra(e).len(), 4 * (degree + 1));
                for (j, a) in facet_node_list(&m, f).into_iter().enumerate() {
                    let mut got: Vec<(u32, f64)> = s.stencil(e)[j]
                        .iter()
                        .map(|&(i, wi)| (ext[i as usize], wi))
                        .collect();
                    let mut want = w[&a].to_vec();
                    got.sort_by_key(|p| p.0);
                    want.sort_by_key(|p| p.0);
                    assert_eq!(got, want);
                }
            }
        }
    }
}
