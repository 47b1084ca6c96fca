//! Structured mesh of the annulus Ri ≤ |X| ≤ Ro with exact circular geometry.
//!
//! Cells: `n_r` radially × `n_theta` circumferentially, cell `j · n_theta + k` (j radial layer
//! from the hub outwards, k counter-clockwise). Degree-p cells have `p·n_r + 1` node rings with
//! `p·n_theta` nodes each; node `ring · per_ring + pos`, positions counter-clockwise starting at
//! θ = -π/2 (the bottom of the cylinder, where the road is), so the mesh is periodic in θ and
//! every ring is a closed streamline.
//!
//! Grading: radial cell sizes form a geometric sequence whose last/first ratio is `grading_r`.
//! Circumferentially, cell boundaries are θ_k = -π/2 + s_k − g sin s_k with s_k uniform in
//! [0, 2π) and g = `grading_theta` ∈ [0, 1): the spacing at the bottom is (1 − g) times the
//! uniform spacing and (1 + g) times at the top. g = 0 gives a uniform mesh.
//!
//! Node sets: `hub` (ring 0), `outer` (last ring). Facet sets: `outer` (side ξ = +1 of the outer
//! layer of cells), `hub` (side ξ = -1 of the inner layer).

use super::{CellGeometry, Facet, Mesh, RingLayout};
use crate::math::Vec2;
use std::collections::BTreeMap;
use std::f64::consts::{FRAC_PI_2, PI};

#[derive(Clone, Debug, PartialEq)]
pub struct AnnulusSpec {
    pub ri: f64,
    pub ro: f64,
    pub n_r: usize,
    pub n_theta: usize,
    /// 1 (Q1) or 2 (Q2).
    pub degree: usize,
    pub grading_r: f64,
    pub grading_theta: f64,
}

/// Radii of the `n_r + 1` cell boundaries.
pub fn radial_breaks(spec: &AnnulusSpec) -> Vec<f64> {
    let n = spec.n_r;
    let q = if n > 1 {
        spec.grading_r.powf(1.0 / (n as f64 - 1.0))
    } else {
        1.0
    };
    let sizes: Vec<f64> = (0..n).map(|j| q.powi(j as i32)).collect();
    let total: f64 = sizes.iter().sum();
    let mut r = Vec::with_capacity(n + 1);
    let mut acc = spec.ri;
    r.push(acc);
    for s in &sizes {
        acc += s / total * (spec.ro - spec.ri);
        r.push(acc);
    }
    r[n] = spec.ro;
    r
}

/// Angles of the `n_theta + 1` cell boundaries (the last one is the first plus 2π).
pub fn angular_breaks(spec: &AnnulusSpec) -> Vec<f64> {
    let n = spec.n_theta;
    let g = spec.grading_theta;
    (0..=n)
        .map(|k| {
            let s = 2.0 * PI * k as f64 / n as f64;
            -FRAC_PI_2 + s - g * s.sin()
        })
        .collect()
}

/// Build the structured annulus mesh. The spec must be valid (the scene validation checks
/// Ri < Ro, n_r ≥ 1, n_theta ≥ 3, degree ∈ {1, 2}); invalid specs are clamped, never panic.
pub fn annulus(spec: &AnnulusSpec) -> Mesh {
    let spec = AnnulusSpec {
        n_r: spec.n_r.max(1),
        n_theta: spec.n_theta.max(3),
        degree: spec.degree.clamp(1, 2),
        ..spec.clone()
    };
    annulus_with_breaks(&spec, &radial_breaks(&spec), &angular_breaks(&spec))
}

/// The annulus of `spec`'s degree with the cell boundaries at the radii `rb` (`n_r + 1`,
/// increasing from Ri to Ro) and the angles `tb` (`n_theta + 1`, increasing, the last the
/// first plus 2π): the meshes of a relocation of the cell boundaries (e.g. toward the contact
/// patch), with the node rings kept. `spec.n_r` and `spec.n_theta` are taken from the lengths
/// of the breaks.
pub fn annulus_with_breaks(spec: &AnnulusSpec, rb: &[f64], tb: &[f64]) -> Mesh {
    if rb.len() < 2 || tb.len() < 4 {
        return annulus(spec);
    }
    let p = spec.degree.clamp(1, 2);
    let n_r = rb.len().saturating_sub(1).max(1);
    let n_theta = tb.len().saturating_sub(1).max(3);

    let rings = p * n_r + 1;
    let per_ring = p * n_theta;
    let mut nodes = Vec::with_capacity(rings * per_ring);
    for m in 0..rings {
        let (j, i) = (m / p, m % p);
        let r = if j == n_r {
            rb[n_r]
        } else {
            rb[j] + (rb[j + 1] - rb[j]) * i as f64 / p as f64
        };
        for l in 0..per_ring {
            let (k, i2) = (l / p, l % p);
            let t = tb[k] + (tb[k + 1] - tb[k]) * i2 as f64 / p as f64;
            let (s, c) = t.sin_cos();
            nodes.push(Vec2::new(r * c, r * s));
        }
    }
    let npc = (p + 1) * (p + 1);
    let n_cells = n_r * n_theta;
    let mut conn = Vec::with_capacity(n_cells * npc);
    let mut offsets = Vec::with_capacity(n_cells + 1);
    let mut geometry = Vec::with_capacity(n_cells);
    offsets.push(0);
    for j in 0..n_r {
        for k in 0..n_theta {
            for b in 0..=p {
                for a in 0..=p {
                    let ring = p * j + a;
                    let pos = (p * k + b) % per_ring;
                    conn.push((ring * per_ring + pos) as u32);
                }
            }
            offsets.push(conn.len());
            geometry.push(CellGeometry::Polar {
                r0: rb[j],
                r1: rb[j + 1],
                t0: tb[k],
                t1: tb[k + 1],
            });
        }
    }
    let mut node_sets = BTreeMap::new();
    node_sets.insert("hub".to_string(), (0..per_ring as u32).collect());
    node_sets.insert(
        "outer".to_string(),
        (((rings - 1) * per_ring) as u32..(rings * per_ring) as u32).collect(),
    );
    let mut facet_sets = BTreeMap::new();
    facet_sets.insert(
        "hub".to_string(),
        (0..n_theta)
            .map(|k| Facet {
                cell: k as u32,
                side: 0,
            })
            .collect(),
    );
    facet_sets.insert(
        "outer".to_string(),
        (0..n_theta)
            .map(|k| Facet {
                cell: ((n_r - 1) * n_theta + k) as u32,
                side: 1,
            })
            .collect(),
    );
    Mesh {
        nodes,
        conn,
        offsets,
        degree: vec![p as u8; n_cells],
        geometry,
        node_sets,
        facet_sets,
        rings: Some(RingLayout {
            rings,
            per_ring,
            n_r,
            n_theta,
            degree: p,
        }),
        regions: vec![0; n_cells],
        region_names: vec!["all".to_string()],
        constraints: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::{Lagrange2D, Q2};

    fn spec(p: usize) -> AnnulusSpec {
        AnnulusSpec {
            ri: 1.0,
            ro: 2.0,
            n_r: 3,
            n_theta: 8,
            degree: p,
            grading_r: 2.0,
            grading_theta: 0.4,
        }
    }

    #[test]
    fn nodes_on_rings_and_cells_consistent() {
        for p in [1, 2] {
            let m = annulus(&spec(p));
            let rl = m.rings.unwrap();
            assert_eq!(m.n_nodes(), rl.rings * rl.per_ring);
            // Nodes of one ring share a radius and go counter-clockwise.
            for ring in 0..rl.rings {
                let r0 = m.nodes[ring * rl.per_ring].norm();
                for pos in 0..rl.per_ring {
                    assert!((m.nodes[ring * rl.per_ring + pos].norm() - r0).abs() < 1e-13);
                }
            }
            assert!((m.nodes[0] - Vec2::new(0.0, -1.0)).norm() < 1e-14);
            // Node positions equal the exact polar map at the nodes' reference coordinates.
            for c in 0..m.n_cells() {
                for (a, &n) in m.cell_nodes(c).iter().enumerate() {
                    let (xi, eta) = if p == 2 {
                        Q2::node_ref(a)
                    } else {
                        crate::element::Q1::node_ref(a)
                    };
                    let (x, _) = m.geometry[c].polar_map(xi, eta).unwrap();
                    assert!(
                        (x - m.nodes[n as usize]).norm() < 1e-13,
                        "cell {c} node {a}"
                    );
                }
            }
            let rb = radial_breaks(&spec(p));
            let ratio = (rb[3] - rb[2]) / (rb[1] - rb[0]);
            assert!((ratio - 2.0).abs() < 1e-12);
        }
    }

    #[test]
    fn polar_area_is_exact() {
        let m = annulus(&spec(2));
        let rule = crate::element::QuadRule::gauss_2d(3);
        let mut area = 0.0;
        for g in &m.geometry {
            for (pt, w) in rule.points.iter().zip(&rule.weights) {
                let (_, j) = g.polar_map(pt.0, pt.1).unwrap();
                area += j.determinant() * w;
            }
        }
        assert!((area - PI * 3.0).abs() < 1e-12, "area {area}");
    }
}
