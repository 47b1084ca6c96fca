//! Strain-rate damping in the three-dimensional steady (θ-referential) mode.
//!
//! The transient mode damps with S_v = η Ė, Ė = ½ (Ḟᵀ F + Fᵀ Ḟ), Ḟ = ∇_X v_h, where v_h is the
//! interpolant of the nodal material velocities ([`super::kernel::viscous_cell`]). In steady
//! rolling the material velocity at the referential position X is v = ω ∂θχ, and the steady
//! mode builds the same conforming field as the plane-strain program does
//! ([`crate::physics::ring_derivative`]): nodal velocities
//!
//! ```text
//! v_a = ω (t_a + (∂θu)_a),   t_a = ∂θX_a = (−X2, X1, 0),   (∂θu)_a = Σ_k W_ak u_k,
//! ```
//!
//! with W_ak the five-point Lagrange derivative weights along the node's ring (nodes of one
//! reference radius and axial position, [`crate::contact::steady_slip3d::ring_weights_of`];
//! fourth order whatever the spacing), and v_h = Σ_a N_a v_a. (The elementwise gradient of
//! ω ∂θχ_h, discontinuous across the cell faces θ = const, converges to another solution; see
//! the plane-strain program's ring derivative.)
//!
//! A cell's viscous residual then depends on the displacements of its own nodes (through F and
//! the stencil centres) and of the stencil nodes beyond it: two past each θ-end on each of its
//! rings. The cell's damping element is its nodes followed by those extra nodes, with the exact
//! tangent
//!
//! ```text
//! ∂r/∂u_q = (∂r/∂u)|_v δ_q∈cell + Σ_a ω W_aq ∂r/∂v_a,
//! ```
//!
//! assembled as a block of its own whose rows are the cell's (the extra nodes' rows are out
//! of the pattern): the Newton matrix holds the whole coupling and Newton converges
//! quadratically with a direct solve.

use super::kernel::Inadmissible;
use super::solid3d::Solid3D;
use crate::contact::steady_slip3d::ring_weights_of;
use crate::mesh::hex_mesh::HexMesh;
use crate::physics::ring_derivative::WIDTH;

/// Most nodes of a cell (Hex27).
const MAX_CELL_NODES: usize = 27;
/// Most stencil nodes of a cell beyond it (Hex27: 4 per ring × 9 rings).
pub const MAX_EXTRA_NODES: usize = 36;
/// Most dofs of a cell's damping element.
pub const MAX_DAMPING_DOFS: usize = 3 * (MAX_CELL_NODES + MAX_EXTRA_NODES);

/// The cells' ring stencils of the steady strain-rate damping.
#[derive(Clone, Debug)]
pub struct SteadyViscosity3D {
    /// Per cell, the stencil nodes beyond it (`extra[off[c]..off[c + 1]]`).
    extra: Vec<u32>,
    off: Vec<usize>,
    /// Per cell and cell node a, the extended local nodes of a's stencil (the cell's nodes
    /// 0..N, then its extra nodes).
    local: Vec<[[u8; WIDTH]; MAX_CELL_NODES]>,
    /// Per node, the stencil weights W_ak (in the order of `local`).
    weights: Vec<[f64; WIDTH]>,
}

impl SteadyViscosity3D {
    /// `None` when the mesh's nodes do not form rings of at least five nodes with distinct
    /// angles about the axle (a mesh that is not a body of revolution's) or a cell would
    /// need more than [`MAX_EXTRA_NODES`] nodes beyond it.
    pub fn new(mesh: &HexMesh) -> Option<Self> {
        let groups = (0..mesh.n_cells()).map(|c| mesh.cell_nodes(c).to_vec());
        let rings = ring_weights_of(mesh, groups)?;
        let mut weights = vec![[0.0; WIDTH]; mesh.n_nodes()];
        let mut stencil_nodes = vec![[0u32; WIDTH]; mesh.n_nodes()];
        for (&a, st) in &rings {
            for (k, &(b, w)) in st.iter().enumerate() {
                weights[a as usize][k] = w;
                stencil_nodes[a as usize][k] = b;
            }
        }
        if rings.len() != mesh.n_nodes() {
            return None;
        }
        let mut extra = Vec::new();
        let mut off = vec![0];
        let mut local = Vec::with_capacity(mesh.n_cells());
        for c in 0..mesh.n_cells() {
            let cn = mesh.cell_nodes(c);
            let mut mine: Vec<u32> = Vec::new();
            let mut loc = [[0u8; WIDTH]; MAX_CELL_NODES];
            for (a, &n) in cn.iter().enumerate() {
                for (k, &b) in stencil_nodes[n as usize].iter().enumerate() {
                    let i = match cn.iter().position(|&m| m == b) {
                        Some(i) => i,
                        None => match mine.iter().position(|&m| m == b) {
                            Some(i) => cn.len() + i,
                            None => {
                                mine.push(b);
                                cn.len() + mine.len() - 1
                            }
                        },
                    };
                    loc[a][k] = i as u8;
                }
            }
            if mine.len() > MAX_EXTRA_NODES {
                return None;
            }
            extra.extend_from_slice(&mine);
            off.push(extra.len());
            local.push(loc);
        }
        Some(Self {
            extra,
            off,
            local,
            weights,
        })
    }

    /// The stencil nodes of cell `c` beyond it, in the order of its damping element.
    pub fn extra(&self, c: usize) -> &[u32] {
        &self.extra[self.off[c]..self.off[c + 1]]
    }

    /// The damping of cell `c` at ω: `ue` holds the displacements of the cell's damping
    /// element (its nodes, then [`Self::extra`], 3 per node); the residual goes into the
    /// first 3N entries of `r`, the tangent (unless `k` is empty) into `k`, row-major with the
    /// element's dof count as row length, the rows past 3N untouched.
    #[allow(clippy::too_many_arguments)]
    pub fn cell(
        &self,
        solid: &Solid3D,
        c: usize,
        ue: &[f64],
        omega: f64,
        eta: f64,
        r: &mut [f64],
        k: &mut [f64],
    ) -> Result<(), Inadmissible> {
        let mesh = &solid.mesh;
        let cn = mesh.cell_nodes(c);
        let (n, nd) = (cn.len(), ue.len());
        let loc = &self.local[c];
        let mut v = [0.0; 3 * MAX_CELL_NODES];
        for (a, &na) in cn.iter().enumerate() {
            let x = mesh.nodes[na as usize];
            let w = &self.weights[na as usize];
            let mut d = [-x[1], x[0], 0.0];
            for (kk, &q) in loc[a].iter().enumerate() {
                for (i, di) in d.iter_mut().enumerate() {
                    *di += w[kk] * ue[3 * q as usize + i];
                }
            }
            for i in 0..3 {
                v[3 * a + i] = omega * d[i];
            }
        }
        let with_k = !k.is_empty();
        let mut kv = [0.0; (3 * MAX_CELL_NODES) * (3 * MAX_CELL_NODES)];
        let kv = &mut kv[..if with_k { 9 * n * n } else { 0 }];
        solid.cell_viscous_split(c, &ue[..3 * n], &v[..3 * n], eta, nd, r, k, kv)?;
        if !with_k {
            return Ok(());
        }
        // ∂r/∂u_q += Σ_a ω W_aq ∂r/∂v_a, componentwise.
        for (a, &na) in cn.iter().enumerate() {
            let w = &self.weights[na as usize];
            for (kk, &q) in loc[a].iter().enumerate() {
                let s = omega * w[kk];
                let q = q as usize;
                for row in 0..3 * n {
                    let kr = &kv[row * 3 * n + 3 * a..row * 3 * n + 3 * a + 3];
                    let out = &mut k[row * nd + 3 * q..row * nd + 3 * q + 3];
                    for i in 0..3 {
                        out[i] += s * kr[i];
                    }
                }
            }
        }
        Ok(())
    }
}
