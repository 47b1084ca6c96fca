//! Steady rolling of the three-dimensional body with a viscoelastic material: the internal
//! variables integrated exactly along the rings of quadrature points of the revolved mesh, and
//! the ring coupling of the consistent tangent, as in plane strain
//! ([`crate::physics::viscoelastic_steady`], whose module docs give the equations).
//!
//! **Rings.** The revolved mesh maps its cross-section independently of θ, so the points of the
//! stiffness rule with the same local (radial, axial) position in the cells of one
//! (radial, axial) layer lie on one circle about the axle (exactly for the exact maps, within
//! the interpolation error of the arc for isoparametric cells). Each such set is sorted by the
//! polar angle θ = atan2(X2, X1) and checked: at least 8 points, none off the first point's
//! circle by more than 1 % of its radius, no gap of more than a quarter turn. Meshes without
//! the revolved layout (Gmsh files) or of mixed degree are refused.
//!
//! **Components.** In the θ-referential description the material now at θ was at θ − ω s a time
//! s ago, rotated with the body about x3. The streamline ODE `ω ∂θX + X/τ_i = f_i(E, ω ∂θE)`
//! therefore holds for the components in the co-rotating cylindrical basis (e_r, e_θ, e_3) of
//! each point: the six components `[rr, θθ, 33, θ3, r3, rθ]` of the strains are integrated
//! along each ring by the exact exponential recurrence and its closed-form periodic solution
//! ([`crate::material::viscoelastic_ring::periodic_affine`]), and the internal variables are
//! rotated back to Cartesian components for the kernels, which evaluate the overstress with
//! Δt = 0 ([`super::kernel::CellOverstress`]).
//!
//! **Tangent.** The kernels assemble the tangent with the state frozen (plus the instantaneous
//! response of the convolution model). The rest, `δP = F δS` with
//! `δS = γ Σ_i (L_i − g_i) δE` (convolution) or `δS = −Σ_i 2 μ_i C_v,i⁻¹ (L_i δE) C_v,i⁻¹`
//! (multiplicative), `δE = sym(Fᵀ ∇δu)` and `L_i` the ring operator, is applied matrix-free by
//! [`SteadyHistory3D::apply_correction`] (two ring sweeps per term and component); Newton solves
//! with the exact tangent by GMRES preconditioned with the factorization of the assembled part.

use super::solid3d::{Solid3D, MAX_POINTS_3D};
use crate::assembly::{DofMap, CONSTRAINED};
use crate::material::viscoelastic::{green_strain, ViscoModel, Viscoelastic};
use crate::material::viscoelastic_ring::{sweep_ring, RingScratch};
use crate::math::{Mat3, Tensor};

/// Fewest points of a ring (fewer cannot be a closed streamline of a revolved mesh).
const MIN_RING: usize = 8;

/// The steady viscoelastic history of the three-dimensional body (see the module docs).
#[derive(Clone, Debug)]
pub struct SteadyHistory3D {
    /// Global point indices (into the solid's history) of each ring, counter-clockwise.
    rings: Vec<Vec<u32>>,
    /// Angle from each ring point to the next counter-clockwise.
    dtheta: Vec<Vec<f64>>,
    /// (cos φ, sin φ) of each point's polar angle.
    rot: Vec<(f64, f64)>,
    /// F = I + ∇u at each point at the last [`Self::sync`].
    f: Vec<Mat3>,
    /// Quadrature weight w_q det J of each point.
    w: Vec<f64>,
    /// Per-point cylindrical strains (or their variations): scratch.
    e: Vec<[f64; 6]>,
    /// Per-point Cartesian strain variations: scratch.
    de: Vec<Mat3>,
    /// Ring output per point, term and component: scratch.
    xs: Vec<f64>,
    /// Full-length scratch.
    full: Vec<f64>,
    /// Ring scratch.
    scratch: RingScratch,
}

/// Cylindrical components `Rᵀ A R` (R = [e_r e_θ e_3] at angle φ, `rot` = (cos φ, sin φ)) of a
/// symmetric Cartesian tensor, in the Voigt layout of [`Tensor::sym_from`].
fn to_cylindrical(a: &Mat3, rot: (f64, f64)) -> [f64; 6] {
    let r = rotation(rot);
    let mut out = [0.0; 6];
    (r.transpose() * a * r).sym_store(&mut out);
    out
}

/// The inverse of [`to_cylindrical`]: `R P Rᵀ`.
fn from_cylindrical(p: &[f64], rot: (f64, f64)) -> Mat3 {
    let r = rotation(rot);
    r * Mat3::sym_from(p) * r.transpose()
}

fn rotation((c, s): (f64, f64)) -> Mat3 {
    Mat3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

impl SteadyHistory3D {
    /// The rings of the quadrature points of `solid` (viscoelastic, its history allocated by
    /// [`Solid3D::set_viscoelastic`]), or why the mesh has none.
    pub fn new(solid: &Solid3D, dofs: &DofMap) -> Result<Self, String> {
        let hist = &solid.history;
        let nc = solid.mesh.n_cells();
        if solid.viscoelastic.is_none() || hist.offsets.len() != nc + 1 {
            return Err("the material has no viscoelastic history".into());
        }
        let n_pts = hist.offsets[nc];
        let zero = vec![0.0; dofs.eq.len()];
        let mut pos = vec![[0.0; 3]; n_pts];
        let mut buf = [([0.0; 3], 0.0, Mat3::zeros()); MAX_POINTS_3D];
        for c in 0..nc {
            let np = solid
                .cell_point_gradients(c, dofs, &zero, &mut buf)
                .map_err(|_| format!("cell {c} is degenerate"))?;
            if np != hist.points_in_cell(c) {
                return Err(format!("cell {c}: history of the wrong size"));
            }
            for (q, b) in buf[..np].iter().enumerate() {
                pos[hist.offsets[c] + q] = b.0;
            }
        }
        let radius = |p: &[f64; 3]| p[0].hypot(p[1]);
        let not_rings = || {
            "the viscoelastic history of the steady mode is integrated along rings of \
             quadrature points about the axle, and the mesh's points do not form such rings \
             (use a generated revolved mesh of one degree)"
                .to_string()
        };
        // The revolved mesh's cells are numbered (layer · n_r + j) · n_theta + k, and the
        // points of a cell's rule (Q per direction) i + Q (j + Q k) along (ξ_r, ξ_θ, ξ_z).
        let layout = solid.mesh.rings.ok_or_else(not_rings)?;
        let deg = solid.mesh.degree.first().copied().unwrap_or(1);
        let q = if deg == 1 { 2 } else { 3 };
        if nc != layout.n_r * layout.n_z * layout.n_theta
            || solid.mesh.degree.iter().any(|&d| d != deg)
            || (0..nc).any(|c| hist.points_in_cell(c) != q * q * q)
        {
            return Err(not_rings());
        }
        let n_rings = layout.n_r * layout.n_z * q * q;
        let mut rings: Vec<Vec<u32>> = vec![Vec::with_capacity(layout.n_theta * q); n_rings];
        for c in 0..nc {
            let layer = c / layout.n_theta;
            for p in 0..q * q * q {
                let (i, k) = (p % q, p / (q * q));
                rings[(layer * q + k) * q + i].push((hist.offsets[c] + p) as u32);
            }
        }
        let angle = |i: u32| {
            let p = pos[i as usize];
            p[1].atan2(p[0]).rem_euclid(2.0 * std::f64::consts::PI)
        };
        let mut dtheta = Vec::with_capacity(rings.len());
        for ring in rings.iter_mut() {
            let m = ring.len();
            if m < MIN_RING {
                return Err(not_rings());
            }
            ring.sort_by(|&a, &b| angle(a).total_cmp(&angle(b)));
            let (r0, z0) = (radius(&pos[ring[0] as usize]), pos[ring[0] as usize][2]);
            let mut d = Vec::with_capacity(m);
            for k in 0..m {
                let p = &pos[ring[(k + 1) % m] as usize];
                // Isoparametric cells place the points on the interpolated arc, within a small
                // fraction of the radius of the circle (the plane-strain rings' tolerance).
                if (radius(p) - r0).abs() > 1e-2 * r0 || (p[2] - z0).abs() > 1e-2 * r0 {
                    return Err(not_rings());
                }
                let mut t = angle(ring[(k + 1) % m]) - angle(ring[k]);
                if k + 1 == m {
                    t += 2.0 * std::f64::consts::PI;
                }
                if t <= 1e-12 || t > 0.5 * std::f64::consts::PI {
                    return Err(not_rings());
                }
                d.push(t);
            }
            dtheta.push(d);
        }
        let rot = pos
            .iter()
            .map(|p| {
                let r = radius(p).max(f64::MIN_POSITIVE);
                (p[0] / r, p[1] / r)
            })
            .collect();
        Ok(Self {
            rings,
            dtheta,
            rot,
            f: vec![Mat3::identity(); n_pts],
            w: vec![0.0; n_pts],
            e: vec![[0.0; 6]; n_pts],
            de: vec![Mat3::zeros(); n_pts],
            xs: Vec::new(),
            full: Vec::new(),
            scratch: RingScratch::default(),
        })
    }

    /// Number of rings.
    pub fn n_rings(&self) -> usize {
        self.rings.len()
    }

    /// Dissipation rate `∫ D dV` of the multiplicative model over the body at the state of the
    /// last [`Self::sync`] (power, the scene's force × length / time; `None` for the
    /// convolution model, which has no free energy). In steady rolling without other
    /// dissipation it balances the power of the hub torque, `M3 ω`.
    pub fn dissipation(&self, solid: &Solid3D) -> Option<f64> {
        let ve = solid.viscoelastic?;
        let ns = solid.history.n_state;
        let mut d = 0.0;
        for (i, (f, w)) in self.f.iter().zip(&self.w).enumerate() {
            let h = f - Mat3::identity();
            d += w * ve.dissipation_rate(&h, &solid.history.data[i * ns..(i + 1) * ns])?;
        }
        Some(d)
    }

    /// For each ring, Prony term and component, the periodic solution `X = L_i e` of the exact
    /// step recurrence driven by the per-point cylindrical strains `self.e`, into `self.xs`
    /// (point-major, then term, then component).
    fn sweep(&mut self, ve: &Viscoelastic, omega: f64) {
        let nt = ve.prony().len();
        self.xs.resize(self.e.len() * 6 * nt, 0.0);
        let (e, xs) = (&self.e, &mut self.xs);
        let mut out =
            |p: usize, term: usize, comp: usize, v: f64| xs[(p * nt + term) * 6 + comp] = v;
        for (pts, dth) in self.rings.iter().zip(&self.dtheta) {
            sweep_ring(
                pts,
                dth,
                ve,
                omega,
                6,
                |p, c| e[p][c],
                &mut out,
                &mut self.scratch,
            );
        }
    }

    /// Replace the history of `solid` by the periodic steady state of the full state `x` at
    /// angular speed `omega` (ω ∂θ along the rings; ω = 0: relaxed). Call before every
    /// evaluation of the residual; the kernels then evaluate the overstress with Δt = 0. A
    /// degenerate cell leaves its points' state as it was (the residual then fails there).
    pub fn sync(&mut self, solid: &mut Solid3D, dofs: &DofMap, x: &[f64], omega: f64) {
        let Some(ve) = solid.viscoelastic else {
            return;
        };
        let ns = solid.history.n_state;
        let mut buf = [([0.0; 3], 0.0, Mat3::zeros()); MAX_POINTS_3D];
        for c in 0..solid.mesh.n_cells() {
            let Ok(np) = solid.cell_point_gradients(c, dofs, x, &mut buf) else {
                continue;
            };
            let o = solid.history.offsets[c];
            for (q, b) in buf[..np].iter().enumerate() {
                let i = o + q;
                self.f[i] = Mat3::identity() + b.2;
                self.w[i] = b.1;
                let e = green_strain(&b.2);
                e.sym_store(&mut solid.history.data[i * ns..i * ns + 6]);
                self.e[i] = to_cylindrical(&e, self.rot[i]);
            }
        }
        self.sweep(&ve, omega);
        let nt = ve.prony().len();
        let data = &mut solid.history.data;
        for (pt, rot) in self.rot.iter().enumerate() {
            for term in 0..nt {
                let o = (pt * nt + term) * 6;
                let xc = from_cylindrical(&self.xs[o..o + 6], *rot);
                let s = pt * ns + 6 * (1 + term);
                xc.sym_store(&mut data[s..s + 6]);
            }
        }
    }

    /// `out += (K − K_kernels) v`: the part of the exact steady tangent that the element
    /// kernels do not assemble (see the module docs), for `v` and `out` in equation numbering,
    /// at the state of the last [`Self::sync`].
    pub fn apply_correction(
        &mut self,
        solid: &Solid3D,
        dofs: &DofMap,
        omega: f64,
        v: &[f64],
        out: &mut [f64],
    ) {
        let Some(ve) = solid.viscoelastic else {
            return;
        };
        let mut full = std::mem::take(&mut self.full);
        full.clear();
        full.resize(dofs.eq.len(), 0.0);
        dofs.scatter_free(v, &mut full);
        let nc = solid.mesh.n_cells();
        let mut buf = [([0.0; 3], 0.0, Mat3::zeros()); MAX_POINTS_3D];
        for c in 0..nc {
            let Ok(np) = solid.cell_point_gradients(c, dofs, &full, &mut buf) else {
                continue;
            };
            let o = solid.history.offsets[c];
            for (q, b) in buf[..np].iter().enumerate() {
                let i = o + q;
                let ft_dh = self.f[i].transpose() * b.2;
                let de = (ft_dh + ft_dh.transpose()) * 0.5;
                self.de[i] = de;
                self.e[i] = to_cylindrical(&de, self.rot[i]);
            }
        }
        self.sweep(&ve, omega);
        let ns = solid.history.n_state;
        let nt = ve.prony().len();
        let state = &solid.history.data;
        let mut dp = [Mat3::zeros(); MAX_POINTS_3D];
        for c in 0..nc {
            let o = solid.history.offsets[c];
            let np = solid.history.points_in_cell(c);
            for (q, dpq) in dp[..np].iter_mut().enumerate() {
                let pt = o + q;
                let mut ds = Mat3::zeros();
                for (i, &(g, _)) in ve.prony().iter().enumerate() {
                    let k = (pt * nt + i) * 6;
                    let dxi = from_cylindrical(&self.xs[k..k + 6], self.rot[pt]);
                    match ve.model {
                        ViscoModel::Convolution => ds += (dxi - self.de[pt] * g) * ve.gamma,
                        ViscoModel::Multiplicative => {
                            let mu = 0.5 * ve.gamma * g;
                            let s = pt * ns + 6 * (1 + i);
                            let cv = Mat3::identity() + Mat3::sym_from(&state[s..s + 6]) * 2.0;
                            let gi = cv.try_inverse().unwrap_or(Mat3::zeros());
                            ds -= gi * dxi * gi * (2.0 * mu);
                        }
                    }
                }
                *dpq = self.f[pt] * ds;
            }
            let _ = solid.cell_divergence(c, dofs, &dp[..np], |d, y| {
                let e = dofs.eq[d];
                if e < CONSTRAINED {
                    out[e as usize] += y;
                }
            });
        }
        self.full = full;
    }
}
