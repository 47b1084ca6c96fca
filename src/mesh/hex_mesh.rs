//! Meshes of hexahedral cells (the three-dimensional body) with exact cylindrical geometry.
//!
//! # Frame
//!
//! The axle is x3; x1 points along the road, x2 up. The body is centred at the origin, the road
//! is the plane x2 = −H in the unloaded state, the body spins about +x3 with ω > 0
//! (counter-clockwise seen from +x3). The wheel's mid-plane is x3 = 0 and its width W; the 2D
//! plane-strain program works in the slice x3 = 0 of this frame.
//!
//! Cells are tensor-product hexahedra of [`crate::element::hex`] (local node
//! `a = i + m·j + m²·k`, ξ radial, η circumferential, ζ axial). Faces are numbered as there
//! (0: ξ = −1, 1: ξ = +1, 2: η = −1, 3: η = +1, 4: ζ = −1, 5: ζ = +1).

use crate::element::hex::{iso_map, Hex27, Hex8};
use nalgebra::{Matrix3, Vector3};
use std::collections::BTreeMap;

/// Geometry map of a hexahedral cell from [-1, 1]³ to the reference configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HexGeometry {
    /// Exact cylindrical map: X = (r cos θ, r sin θ, x3) with r affine in ξ from `r0` to `r1`,
    /// θ affine in η from `t0` to `t1`, x3 affine in ζ from `z0` to `z1` (the 2D polar map
    /// extruded along the axle).
    Cylindrical {
        r0: f64,
        r1: f64,
        t0: f64,
        t1: f64,
        z0: f64,
        z1: f64,
    },
    /// Crowned cylindrical map: r = ri + (r_outer(x3) − ri) s, with s affine in ξ from `s0` to
    /// `s1` (s ∈ [0, 1], fraction of the local wall thickness) and
    /// r_outer(x3) = ro − (rc − sqrt(rc² − x3²)) the torus of crown radius `rc`; θ and x3 as in
    /// `Cylindrical`.
    Crowned {
        s0: f64,
        s1: f64,
        t0: f64,
        t1: f64,
        z0: f64,
        z1: f64,
        ri: f64,
        ro: f64,
        rc: f64,
    },
    /// Isoparametric: X = Σ N_a X_a with the cell's own shape functions.
    Isoparametric,
}

/// Outer radius r_outer(x3) = ro − (rc − sqrt(rc² − x3²)) of a crowned wheel and its derivative.
#[inline]
pub fn crown_profile(ro: f64, rc: f64, z: f64) -> (f64, f64) {
    let q = (rc * rc - z * z).max(0.0).sqrt();
    let d = if q > 0.0 { -z / q } else { 0.0 };
    (ro - (rc - q), d)
}

impl HexGeometry {
    /// Position and Jacobian dX/dξ (`jac[(i, k)] = ∂X_i/∂ξ_k`) of an exact cell map at `x`;
    /// `None` for isoparametric cells (use [`HexMesh::map`]).
    #[inline]
    pub fn exact_map(&self, x: [f64; 3]) -> Option<(Vector3<f64>, Matrix3<f64>)> {
        let (r, dr_dxi, dr_dzeta, t, dt, z, dz) = match *self {
            HexGeometry::Cylindrical {
                r0,
                r1,
                t0,
                t1,
                z0,
                z1,
            } => {
                let r = r0 + 0.5 * (r1 - r0) * (1.0 + x[0]);
                let t = t0 + 0.5 * (t1 - t0) * (1.0 + x[1]);
                let z = z0 + 0.5 * (z1 - z0) * (1.0 + x[2]);
                (
                    r,
                    0.5 * (r1 - r0),
                    0.0,
                    t,
                    0.5 * (t1 - t0),
                    z,
                    0.5 * (z1 - z0),
                )
            }
            HexGeometry::Crowned {
                s0,
                s1,
                t0,
                t1,
                z0,
                z1,
                ri,
                ro,
                rc,
            } => {
                let s = s0 + 0.5 * (s1 - s0) * (1.0 + x[0]);
                let t = t0 + 0.5 * (t1 - t0) * (1.0 + x[1]);
                let z = z0 + 0.5 * (z1 - z0) * (1.0 + x[2]);
                let dz = 0.5 * (z1 - z0);
                let (rout, drout) = crown_profile(ro, rc, z);
                (
                    ri + (rout - ri) * s,
                    (rout - ri) * 0.5 * (s1 - s0),
                    drout * s * dz,
                    t,
                    0.5 * (t1 - t0),
                    z,
                    dz,
                )
            }
            HexGeometry::Isoparametric => return None,
        };
        let (sn, cs) = t.sin_cos();
        let pos = Vector3::new(r * cs, r * sn, z);
        let jac = Matrix3::new(
            dr_dxi * cs,
            -r * sn * dt,
            dr_dzeta * cs,
            dr_dxi * sn,
            r * cs * dt,
            dr_dzeta * sn,
            0.0,
            0.0,
            dz,
        );
        Some((pos, jac))
    }
}

/// A face of a hexahedral cell (numbering of [`crate::element::hex`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HexFacet {
    pub cell: u32,
    /// 0..6: ξ = ∓1, η = ∓1, ζ = ∓1.
    pub face: u8,
}

/// Ring structure of a structured revolved mesh.
///
/// Node `(ring_z · rings_r + ring_r) · per_ring + pos`: each circumferential node line (fixed
/// radial index `ring_r`, fixed axial index `ring_z`) is a closed streamline, positions
/// counter-clockwise from θ = −π/2; each axial node layer is numbered like the 2D annulus.
/// Cell `(layer · n_r + j) · n_theta + k`: the cells of one (j, layer) form a ring.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RingLayout3D {
    /// Radial node lines (p·n_r + 1), axial node lines (p·n_z + 1), nodes per ring (p·n_theta).
    pub rings_r: usize,
    pub rings_z: usize,
    pub per_ring: usize,
    pub n_r: usize,
    pub n_z: usize,
    pub n_theta: usize,
    pub degree: usize,
}

impl RingLayout3D {
    #[inline]
    pub fn node(&self, ring_r: usize, ring_z: usize, pos: usize) -> usize {
        (ring_z * self.rings_r + ring_r) * self.per_ring + pos
    }
    /// (ring_r, ring_z, pos) of a node.
    #[inline]
    pub fn ring_of(&self, node: usize) -> (usize, usize, usize) {
        let ring = node / self.per_ring;
        (
            ring % self.rings_r,
            ring / self.rings_r,
            node % self.per_ring,
        )
    }
    #[inline]
    pub fn cell(&self, j: usize, layer: usize, k: usize) -> usize {
        (layer * self.n_r + j) * self.n_theta + k
    }
}

/// A mesh of hexahedra: reference node positions, CSR connectivity (local tensor order), per-cell
/// degree and geometry, named node and facet sets, regions.
#[derive(Clone, Debug)]
pub struct HexMesh {
    pub nodes: Vec<Vector3<f64>>,
    pub conn: Vec<u32>,
    pub offsets: Vec<usize>,
    /// Polynomial degree of each cell (1: Hex8, 2: Hex27).
    pub degree: Vec<u8>,
    pub geometry: Vec<HexGeometry>,
    pub node_sets: BTreeMap<String, Vec<u32>>,
    pub facet_sets: BTreeMap<String, Vec<HexFacet>>,
    pub rings: Option<RingLayout3D>,
    pub regions: Vec<u16>,
    pub region_names: Vec<String>,
}

impl HexMesh {
    pub fn n_nodes(&self) -> usize {
        self.nodes.len()
    }
    pub fn n_cells(&self) -> usize {
        self.degree.len()
    }
    #[inline]
    pub fn cell_nodes(&self, c: usize) -> &[u32] {
        &self.conn[self.offsets[c]..self.offsets[c + 1]]
    }
    pub fn node_set(&self, name: &str) -> &[u32] {
        self.node_sets.get(name).map(Vec::as_slice).unwrap_or(&[])
    }
    pub fn facet_set(&self, name: &str) -> &[HexFacet] {
        self.facet_sets.get(name).map(Vec::as_slice).unwrap_or(&[])
    }
    /// Make every cell isoparametric (X = Σ N_a X_a from its nodes, which the generators place
    /// on the exact surfaces): the discrete displacement space then contains the rigid motions
    /// exactly (objectivity), as in the plane-strain program.
    pub fn make_isoparametric(&mut self) {
        self.geometry.fill(HexGeometry::Isoparametric);
    }

    /// Position and Jacobian dX/dξ of cell `c` at reference point `x`: the exact map where the
    /// cell has one, else the isoparametric interpolation of its nodes.
    pub fn map(&self, c: usize, x: [f64; 3]) -> (Vector3<f64>, Matrix3<f64>) {
        if let Some(m) = self.geometry[c].exact_map(x) {
            return m;
        }
        let mut xs = [Vector3::zeros(); 27];
        let cn = self.cell_nodes(c);
        for (slot, &n) in xs.iter_mut().zip(cn) {
            *slot = self.nodes[n as usize];
        }
        let mut n = [0.0; 27];
        let mut dn = [[0.0; 3]; 27];
        if self.degree[c] == 1 {
            iso_map::<Hex8>(&xs[..8], x, &mut n, &mut dn)
        } else {
            iso_map::<Hex27>(&xs, x, &mut n, &mut dn)
        }
    }
}
