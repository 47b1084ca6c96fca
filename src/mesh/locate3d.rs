//! Point location in a revolved hexahedral mesh ([`super::revolved`]): which cell holds a
//! reference point X, and at which ξ ∈ [-1, 1]³.
//!
//! The mesh's ring layout ([`RingLayout3D`]) gives the circumferential slab of X from its angle
//! about the axle (the vertex angles of one node ring, sorted); the cells of that slab and of its
//! two neighbours are tried, the map X(ξ) of each inverted by Newton's method, and the cell whose
//! reference point is innermost (smallest max |ξ_i|) wins. A point slightly outside its cell (a
//! point on the exact surface next to a Q2 face, which deviates from it by O(h³)) is accepted
//! up to max |ξ_i| ≤ 1 + [`super::locate::EXTRAPOLATION`].

use super::hex_mesh::{HexMesh, RingLayout3D};
use super::locate::EXTRAPOLATION;
use crate::element::hex::{Hex27, Hex8, Lagrange3D};
use nalgebra::Vector3;
use std::f64::consts::TAU;

/// A located point: its cell and reference coordinates ξ.
pub type Located = (usize, [f64; 3]);

/// The located points of `points` in the revolved mesh `mesh`: (cell, ξ) of each, `None` for a
/// point outside the mesh; `None` altogether for a mesh without a ring layout.
pub fn locate_points_revolved(
    mesh: &HexMesh,
    points: &[Vector3<f64>],
) -> Option<Vec<Option<Located>>> {
    let rl = mesh.rings?;
    if rl.n_theta == 0 || rl.degree == 0 {
        return None;
    }
    let vertex = |k: usize| mesh.nodes[rl.node(0, 0, k * rl.degree)];
    let x0 = vertex(0);
    let t0 = x0[1].atan2(x0[0]);
    let angles: Vec<f64> = (1..rl.n_theta)
        .map(|k| {
            let x = vertex(k);
            (x[1].atan2(x[0]) - t0).rem_euclid(TAU)
        })
        .collect();
    Some(
        points
            .iter()
            .map(|p| {
                let t = (p[1].atan2(p[0]) - t0).rem_euclid(TAU);
                let k = angles.partition_point(|&a| a <= t);
                locate_in_slab(mesh, &rl, k, p)
            })
            .collect(),
    )
}

fn locate_in_slab(
    mesh: &HexMesh,
    rl: &RingLayout3D,
    k: usize,
    p: &Vector3<f64>,
) -> Option<Located> {
    let nt = rl.n_theta;
    let mut best: Option<(usize, [f64; 3], f64)> = None;
    for dk in [0, 1, nt - 1] {
        let kk = (k + dk) % nt;
        for layer in 0..rl.n_z {
            for j in 0..rl.n_r {
                let c = rl.cell(j, layer, kk);
                if let Some(xi) = inverse_map(mesh, c, p) {
                    let m = xi.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                    if best.is_none_or(|b| m < b.2) {
                        best = Some((c, xi, m));
                    }
                }
            }
        }
        if best.is_some_and(|b| b.2 <= 1.0 + 1e-12) {
            break;
        }
    }
    best.filter(|b| b.2 <= 1.0 + EXTRAPOLATION)
        .map(|(c, xi, _)| (c, xi))
}

/// Newton inversion of the map of cell `c`; `None` if it does not converge.
pub fn inverse_map(mesh: &HexMesh, c: usize, p: &Vector3<f64>) -> Option<[f64; 3]> {
    let mut xi = [0.0; 3];
    for _ in 0..40 {
        let (x, jac) = mesh.map(c, xi);
        let r = x - p;
        let d = jac.lu().solve(&r)?;
        for (v, dv) in xi.iter_mut().zip(d.iter()) {
            *v = (*v - dv).clamp(-3.0, 3.0);
        }
        if d.amax() < 1e-13 {
            return Some(xi);
        }
    }
    None
}

/// A field with three components per node (`x[3 n + i]`, e.g. displacements) at ξ of cell
/// `c`.
pub fn vector_at(mesh: &HexMesh, x: &[f64], c: usize, xi: [f64; 3]) -> [f64; 3] {
    let mut n = [0.0; 27];
    let mut dn = [[0.0; 3]; 27];
    let np = if mesh.degree[c] == 1 {
        Hex8::eval(xi, &mut n[..8], &mut dn[..8]);
        8
    } else {
        Hex27::eval(xi, &mut n, &mut dn);
        27
    };
    let mut u = [0.0; 3];
    for (&node, &w) in mesh.cell_nodes(c).iter().zip(&n[..np]) {
        for (i, ui) in u.iter_mut().enumerate() {
            *ui += w * x[3 * node as usize + i];
        }
    }
    u
}
