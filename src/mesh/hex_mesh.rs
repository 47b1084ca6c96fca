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

use crate::element::hex::{face_axis, face_nodes, iso_map, Hex27, Hex8};
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

    /// Global nodes of face `f` of cell `c` in the face's 2D tensor order
    /// ([`crate::element::hex::face_nodes`]): 4 nodes (Hex8) or 9 (Hex27).
    pub fn face_node_ids(&self, c: usize, f: usize) -> Vec<u32> {
        let cn = self.cell_nodes(c);
        let local = if self.degree[c] == 1 {
            face_nodes::<Hex8>(f)
        } else {
            face_nodes::<Hex27>(f)
        };
        local.iter().filter_map(|&a| cn.get(a).copied()).collect()
    }

    /// The centre of a boundary face that faces the circumferential direction (|n · e_θ| > 1/2
    /// there, e_θ about the axle x3), if the mesh has one: the mesh then does not close around
    /// the axle (a sector). `None` for a body of revolution meshed all the way round.
    pub fn circumferential_cut(&self) -> Option<Vector3<f64>> {
        for f in self.boundary_faces() {
            let axis = usize::from(f.face / 2);
            let mut xi = [0.0; 3];
            xi[axis] = if f.face % 2 == 0 { -1.0 } else { 1.0 };
            let (x, jac) = self.map(f.cell as usize, xi);
            let Some(inv) = jac.try_inverse() else {
                continue;
            };
            // The face normal is the gradient of the cell coordinate that is fixed on it.
            let n = inv.transpose().column(axis).into_owned();
            let r = x[0].hypot(x[1]);
            if r <= 0.0 || n.norm() == 0.0 {
                continue;
            }
            let e_theta = Vector3::new(-x[1] / r, x[0] / r, 0.0);
            if n.dot(&e_theta).abs() > 0.5 * n.norm() {
                return Some(x);
            }
        }
        None
    }

    /// The faces that belong to exactly one cell (the boundary of the body), in the order of
    /// their cells and local faces. Two faces are the same when their four corner nodes are.
    pub fn boundary_faces(&self) -> Vec<HexFacet> {
        let mut count: std::collections::HashMap<[u32; 4], u32> =
            std::collections::HashMap::with_capacity(3 * self.n_cells());
        let corners = |c: usize, f: usize| -> [u32; 4] {
            let n = self.face_node_ids(c, f);
            let m = if n.len() == 9 { 2 } else { 1 };
            let w = m + 1;
            let mut k = [n[0], n[m], n[w * m], n[w * m + m]];
            k.sort_unstable();
            k
        };
        for c in 0..self.n_cells() {
            for f in 0..6 {
                *count.entry(corners(c, f)).or_insert(0) += 1;
            }
        }
        let mut out = Vec::new();
        for c in 0..self.n_cells() {
            for f in 0..6 {
                if count.get(&corners(c, f)) == Some(&1) {
                    out.push(HexFacet {
                        cell: c as u32,
                        face: f as u8,
                    });
                }
            }
        }
        out
    }

    /// Triangulation of the faces `faces` for viewers: every quadrilateral of the face's node grid
    /// split along one diagonal (2 triangles per Hex8 face, 8 per Hex27 face, through its 9
    /// nodes), each triangle counter-clockwise seen from outside the cell (for cells with
    /// det J > 0). The vertices are the distinct nodes of the faces in increasing order.
    pub fn surface_triangulation(&self, faces: &[HexFacet]) -> SurfaceTriangulation {
        let mut tris_global: Vec<[u32; 3]> = Vec::with_capacity(8 * faces.len());
        for fc in faces {
            let (c, f) = (fc.cell as usize, usize::from(fc.face));
            let n = self.face_node_ids(c, f);
            let w = if n.len() == 9 { 3 } else { 2 };
            if n.len() != w * w {
                continue;
            }
            // The face's (u, v) tangents give u × v = +outward for faces 0 and 5 (etc.):
            // n dA = s (t_{k+1} × t_{k+2}); for k = 1 the free axes (0, 2) are in reversed
            // cyclic order.
            let (k, s) = face_axis(f);
            let side = if k == 1 { -s } else { s };
            let outward = side > 0.0;
            for iv in 0..w - 1 {
                for iu in 0..w - 1 {
                    let p00 = n[iu + w * iv];
                    let p10 = n[iu + 1 + w * iv];
                    let p01 = n[iu + w * (iv + 1)];
                    let p11 = n[iu + 1 + w * (iv + 1)];
                    if outward {
                        tris_global.push([p00, p10, p11]);
                        tris_global.push([p00, p11, p01]);
                    } else {
                        tris_global.push([p00, p11, p10]);
                        tris_global.push([p00, p01, p11]);
                    }
                }
            }
        }
        let mut vertices: Vec<u32> = tris_global.iter().flatten().copied().collect();
        vertices.sort_unstable();
        vertices.dedup();
        let mut local = vec![u32::MAX; self.n_nodes()];
        for (i, &v) in vertices.iter().enumerate() {
            if let Some(slot) = local.get_mut(v as usize) {
                *slot = i as u32;
            }
        }
        let triangles = tris_global
            .iter()
            .map(|t| t.map(|v| local[v as usize]))
            .collect();
        SurfaceTriangulation {
            vertices,
            triangles,
        }
    }
}

/// A triangulated surface of a [`HexMesh`] (see [`HexMesh::surface_triangulation`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SurfaceTriangulation {
    /// Global node of every vertex.
    pub vertices: Vec<u32>,
    /// Vertex indices (into `vertices`) of every triangle, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
}

#[cfg(test)]
mod tests {
    use crate::mesh::revolved::{revolved, RevolvedSpec};
    use std::collections::HashMap;

    fn spec(p: usize) -> RevolvedSpec {
        RevolvedSpec {
            ri: 1.0,
            ro: 2.0,
            width: 0.6,
            n_r: 2,
            n_z: 3,
            n_theta: 12,
            degree: p,
            grading_r: 1.0,
            grading_theta: 0.0,
            theta_ratio: 1.0,
            grading_z: 1.0,
            half_width: false,
            crown_radius: None,
        }
    }

    #[test]
    fn boundary_faces_are_the_named_facet_sets() {
        for p in [1, 2] {
            let m = revolved(&spec(p)).unwrap();
            let b = m.boundary_faces();
            // hub + outer: 2 n_z n_theta; two sides: 2 n_r n_theta.
            assert_eq!(b.len(), 2 * 3 * 12 + 2 * 2 * 12);
            let mut named: Vec<(u32, u8)> = ["hub", "outer", "side_neg", "side_pos"]
                .iter()
                .flat_map(|s| m.facet_set(s).iter().map(|f| (f.cell, f.face)))
                .collect();
            named.sort_unstable();
            let got: Vec<(u32, u8)> = b.iter().map(|f| (f.cell, f.face)).collect();
            assert_eq!(got, named);
        }
    }

    /// The triangulated boundary is a closed surface oriented outward: every edge is used once
    /// in each direction, and the enclosed volume (divergence theorem, Σ p0·(p1 × p2)/6) is
    /// positive and close to π (ro² − ri²) W (the inscribed polyhedron of 12 p sectors is smaller
    /// by the polygon factor sin(2π/N) N/(2π), N = 12 p).
    #[test]
    fn surface_triangulation_is_closed_and_outward() {
        for p in [1usize, 2] {
            let m = revolved(&spec(p)).unwrap();
            let s = m.surface_triangulation(&m.boundary_faces());
            assert_eq!(s.triangles.len(), (2 * 3 * 12 + 2 * 2 * 12) * 2 * p * p);
            let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
            let mut vol = 0.0;
            for t in &s.triangles {
                for e in 0..3 {
                    let (a, b) = (t[e], t[(e + 1) % 3]);
                    *edges.entry((a.min(b), a.max(b))).or_insert(0) += if a < b { 1 } else { -1 };
                }
                let x = |i: u32| m.nodes[s.vertices[i as usize] as usize];
                vol += x(t[0]).dot(&x(t[1]).cross(&x(t[2]))) / 6.0;
            }
            assert!(edges.values().all(|&c| c == 0));
            let n = (12 * p) as f64;
            let tau = std::f64::consts::TAU;
            let exact = std::f64::consts::PI * (4.0 - 1.0) * 0.6 * (tau / n).sin() * n / tau;
            assert!(
                (vol - exact).abs() < 1e-12 * exact,
                "p = {p}: {vol} vs {exact}"
            );
            // Only boundary nodes are vertices: all nodes minus the interior ones.
            let (nr, nz, nt) = (2 * p + 1, 3 * p + 1, 12 * p);
            assert_eq!(s.vertices.len(), nr * nz * nt - (nr - 2) * (nz - 2) * nt);
        }
    }
}
