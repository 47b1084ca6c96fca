//! The solid's cell integrand, written once for every dimension: plane strain is `D = 2`
//! (F33 = 1, tensors [`crate::math::Mat2`]), the three-dimensional solid `D = 3`
//! ([`crate::math::Mat3`]).
//!
//! For the cell's quadrature points (reference position X, weight w = w_q det J, shape values
//! N_a and gradients G_a = ∇_X N_a) and the cell's nodal displacements u_a, the cell residual is
//!
//! ```text
//! r_ai = Σ_q w [ P_iJ G_aJ − ρ ω² (∂θχ)_i (t · G_a) − b_i N_a ]      (+ pressure rows)
//! ```
//!
//! with F = I + H, H = Σ_a u_a ⊗ G_a, P = ∂W/∂F − p cof F, t = e3 × X the derivative along
//! the circles about the axle (t = (−X2, X1) in the plane, (−X2, X1, 0) in 3D) and
//! ∂θχ = t + H t. The tangent is
//!
//! ```text
//! K_ai,bk = Σ_q w [ G_aJ A_iJ,kL G_bL − ρ ω² δ_ik (t · G_a)(t · G_b) ]
//! ```
//!
//! with A = ∂P/∂F in the flattening `D·i + J` of [`crate::math::Tensor`]. Incompressible laws
//! take a discontinuous P1 pressure per cell, q = [1, (X − X̄)/h] (X̄ the cell's volume
//! centroid, h = |Ω_c|^{1/D}): exact (J − 1 orthogonal to q per cell, the pressures are cell
//! unknowns after the displacements) or perturbed (p = p0 e0 − κ M⁻¹ ∫ (J − 1) q, condensed:
//! K* = K_uu + κ K_up M⁻¹ K_upᵀ with M = ∫ q qᵀ), as the plane-strain element does.
//!
//! Nothing here is specific to a mesh: the caller maps the cell, fills the [`Point`]s and
//! gathers the nodal values; the coefficients (ω², the load factor of a body force) come in a
//! [`Coefficients`] value, not from shared state.

use crate::material::invariants::InvariantTensor;
use crate::material::viscoelastic::MAX_STATE_3D;
use crate::material::{Hyperelastic, Viscoelastic};
use nalgebra::{Matrix4, Vector4};

/// One quadrature point of a cell with `N` nodes in `D` dimensions.
#[derive(Clone, Copy, Debug)]
pub struct Point<const D: usize, const N: usize> {
    /// Reference position X.
    pub x: [f64; D],
    /// Quadrature weight times det dX/dξ.
    pub w: f64,
    /// Shape values N_a.
    pub n: [f64; N],
    /// Shape gradients ∇_X N_a.
    pub g: [[f64; D]; N],
}

impl<const D: usize, const N: usize> Default for Point<D, N> {
    fn default() -> Self {
        Self {
            x: [0.0; D],
            w: 0.0,
            n: [0.0; N],
            g: [[0.0; D]; N],
        }
    }
}

/// Body force per unit reference volume as a function of X.
pub type BodyForceD<const D: usize> = dyn Fn([f64; D]) -> [f64; D] + Send + Sync;

/// How the incompressibility constraint of a cell is imposed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CellPressure<'a> {
    /// Compressible material.
    None,
    /// Exact constraint; the cell's `D + 1` pressure coefficients (in the basis of the module
    /// docs) follow the displacements in the cell's dofs.
    Exact { p: &'a [f64] },
    /// Perturbed Lagrangian with bulk modulus κ and reference pressure p0, condensed.
    Perturbed { kappa: f64, p0: f64 },
}

/// The coefficients of the residual: what the analysis supplies (not flags on the model).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Coefficients {
    /// ω² of the θ-referential inertia (rad²/s²).
    pub omega2: f64,
    /// Factor of the body force (load stepping).
    pub body_load: f64,
    /// The step over which a viscoelastic history advances in this evaluation, from the
    /// committed state (0: the committed state itself, with the instantaneous response to a
    /// change of strain; see [`CellOverstress`]).
    pub history_dt: f64,
}

/// What made a cell inadmissible.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Inadmissible {
    /// J ≤ 0 (or not finite) at a quadrature point.
    Inverted,
    /// The cell map or the pressure mass matrix is singular.
    Singular,
}

/// The material data of a cell.
pub struct CellLaw<'a, M: ?Sized, const D: usize> {
    pub material: &'a M,
    pub rho: f64,
    pub pressure: CellPressure<'a>,
    pub body_force: Option<&'a BodyForceD<D>>,
    /// A viscoelastic overstress and the committed state of the cell's points (in the order
    /// of the points, `n_state` values each), evaluated over the step
    /// [`Coefficients::history_dt`].
    pub overstress: Option<CellOverstress<'a>>,
}

/// The viscoelastic overstress of a cell ([`crate::material::viscoelastic`]): at each point the
/// end-of-step overstress P_v = F S_v from the committed state `old` over the step
/// [`Coefficients::history_dt`] (0: the committed state, with the instantaneous response to a
/// change of strain), added to the stress, its algorithmic tangent ∂P_v/∂F to the material
/// tangent. The state is read, never written: the caller commits it once a step has converged.
#[derive(Clone, Copy)]
pub struct CellOverstress<'a> {
    pub law: &'a Viscoelastic,
    pub old: &'a [f64],
}

/// Number of pressure coefficients per cell of the P1 basis in `D` dimensions.
pub const fn n_pressure(d: usize) -> usize {
    d + 1
}

/// The P1 pressure basis at X: [1, (X − X̄)/h] (padded with zeros to 4 entries).
#[inline]
pub(crate) fn p1_basis<const D: usize>(x: &[f64; D], xc: &[f64; D], h: f64) -> Vector4<f64> {
    let mut q = Vector4::zeros();
    q[0] = 1.0;
    for i in 0..D {
        q[i + 1] = (x[i] - xc[i]) / h;
    }
    q
}

/// Centroid and size h = |Ω_c|^{1/D} of a cell from its quadrature points.
#[allow(clippy::needless_range_loop)] // Index loops spell out the components.
pub(crate) fn pressure_frame<const D: usize, const N: usize>(
    pts: &[Point<D, N>],
) -> ([f64; D], f64) {
    let vol: f64 = pts.iter().map(|p| p.w).sum();
    let mut xc = [0.0; D];
    for p in pts {
        for i in 0..D {
            xc[i] += p.x[i] * p.w;
        }
    }
    if vol > 0.0 {
        xc.iter_mut().for_each(|v| *v /= vol);
    }
    (xc, vol.abs().powf(1.0 / D as f64).max(f64::MIN_POSITIVE))
}

/// H = Σ_a u_a ⊗ G_a.
#[inline]
pub fn grad_u<T: InvariantTensor, const D: usize, const N: usize>(
    u: &[f64],
    g: &[[f64; D]; N],
) -> T {
    let mut h = T::zero();
    for a in 0..N {
        for i in 0..D {
            let ua = u[D * a + i];
            for j in 0..D {
                h[(i, j)] += ua * g[a][j];
            }
        }
    }
    h
}

/// The perturbed cell pressure p = p0 e0 − κ M⁻¹ g and M⁻¹ (padded to 4 × 4 with the
/// identity).
pub(crate) fn perturbed_pressure<T: InvariantTensor, const D: usize, const N: usize>(
    pts: &[Point<D, N>],
    u: &[f64],
    kappa: f64,
    p0: f64,
    frame: &([f64; D], f64),
) -> Result<(Vector4<f64>, Matrix4<f64>), Inadmissible> {
    let np = n_pressure(D);
    let mut m = Matrix4::zeros();
    let mut gv = Vector4::zeros();
    for p in pts {
        let q = p1_basis(&p.x, &frame.0, frame.1);
        let jm1 = grad_u::<T, D, N>(u, &p.g).det_ipm1();
        m += q * q.transpose() * p.w;
        gv += q * (jm1 * p.w);
    }
    for i in np..4 {
        m[(i, i)] = 1.0;
    }
    let minv = m.try_inverse().ok_or(Inadmissible::Singular)?;
    let mut pc = -kappa * (minv * gv);
    pc[0] += p0;
    for i in np..4 {
        pc[i] = 0.0;
    }
    Ok((pc, minv))
}

/// Residual `r` (length nd) and, unless `k` is empty, the row-major tangent `k` (nd × nd) of
/// one cell, added to what they hold. nd = D·N, plus D + 1 with [`CellPressure::Exact`].
/// `u` holds the cell's nodal displacements (D·N, node-major).
#[allow(clippy::needless_range_loop)] // Index loops spell out the index notation of the kernel.
pub fn solid_cell<T, M, const D: usize, const N: usize>(
    pts: &[Point<D, N>],
    u: &[f64],
    law: &CellLaw<'_, M, D>,
    co: &Coefficients,
    r: &mut [f64],
    k: &mut [f64],
) -> Result<(), Inadmissible>
where
    T: InvariantTensor,
    M: Hyperelastic<T> + ?Sized,
{
    debug_assert_eq!(T::D, D);
    let nu = D * N;
    let np = n_pressure(D);
    let with_k = !k.is_empty();
    let exact = matches!(law.pressure, CellPressure::Exact { .. });
    let nd = nu + if exact { np } else { 0 };
    let has_p = !matches!(law.pressure, CellPressure::None);
    let frame = if has_p {
        pressure_frame(pts)
    } else {
        ([0.0; D], 1.0)
    };
    let (pc, minv, kappa) = match law.pressure {
        CellPressure::None => (Vector4::zeros(), Matrix4::zeros(), 0.0),
        CellPressure::Exact { p } => {
            let mut pc = Vector4::zeros();
            for m in 0..np {
                pc[m] = p[m];
            }
            (pc, Matrix4::zeros(), 0.0)
        }
        CellPressure::Perturbed { kappa, p0 } => {
            let (pc, minv) = perturbed_pressure::<T, D, N>(pts, u, kappa, p0, &frame)?;
            (pc, minv, kappa)
        }
    };
    let rw2 = law.rho * co.omega2;
    // K_up (nu × 4), for the exact rows or the condensation.
    let mut kup = [[0.0f64; 4]; 81];
    let mut new_state = [0.0; MAX_STATE_3D];
    for (q, pt) in pts.iter().enumerate() {
        let h: T = grad_u::<T, D, N>(u, &pt.g);
        let jm1 = h.det_ipm1();
        if jm1 <= -1.0 || !jm1.is_finite() {
            return Err(Inadmissible::Inverted);
        }
        let w = pt.w;
        let (mut pk, mut a) = if with_k {
            law.material.stress_tangent(&h)
        } else {
            (law.material.stress(&h), T::tangent_zero())
        };
        if let Some(ov) = law.overstress {
            let ns = ov.law.n_state_of::<T>();
            let old = &ov.old[q * ns..(q + 1) * ns];
            let (pv, av) = ov
                .law
                .overstress(&h, old, co.history_dt, &mut new_state[..ns], with_k);
            if !pv.frob().is_finite() {
                return Err(Inadmissible::Inverted);
            }
            pk = pk + pv;
            a = a + av;
        }
        let f = T::eye() + h;
        let mut q = Vector4::zeros();
        let mut cof = T::zero();
        if has_p {
            q = p1_basis(&pt.x, &frame.0, frame.1);
            let p = pc.dot(&q);
            cof = f.cof();
            pk = pk - cof * p;
            if with_k {
                a = a - T::dcof(&f) * p;
            }
        }
        // t = e3 × X and ∂θχ = t + H t.
        let mut t = [0.0; D];
        t[0] = -pt.x[1];
        t[1] = pt.x[0];
        let mut dth = t;
        for i in 0..D {
            for j in 0..D {
                dth[i] += h[(i, j)] * t[j];
            }
        }
        let mut tg = [0.0; N];
        for b in 0..N {
            tg[b] = (0..D).map(|j| t[j] * pt.g[b][j]).sum();
        }
        let bf = match law.body_force {
            Some(b) if co.body_load != 0.0 => Some(b(pt.x)),
            _ => None,
        };
        for a_ in 0..N {
            let ga = &pt.g[a_];
            for i in 0..D {
                let mut ri = -rw2 * dth[i] * tg[a_];
                for j in 0..D {
                    ri += pk[(i, j)] * ga[j];
                }
                if let Some(b) = bf {
                    ri -= co.body_load * b[i] * pt.n[a_];
                }
                r[D * a_ + i] += ri * w;
            }
        }
        if has_p {
            for a_ in 0..N {
                for i in 0..D {
                    let cg: f64 = (0..D).map(|j| cof[(i, j)] * pt.g[a_][j]).sum();
                    for m in 0..np {
                        kup[D * a_ + i][m] -= cg * q[m] * w;
                    }
                }
            }
            if exact {
                for m in 0..np {
                    r[nu + m] -= jm1 * q[m] * w;
                }
            }
        }
        if !with_k {
            continue;
        }
        // K_ai,bk += w Σ_L (Σ_J G_aJ A_iJ,kL) G_bL − w ρω² δ_ik T_a T_b.
        for a_ in 0..N {
            let ga = &pt.g[a_];
            for i in 0..D {
                let row = (D * a_ + i) * nd;
                // c[k][L] = w Σ_J G_aJ A[(D i + J, D k + L)]
                let mut c = [[0.0; D]; D];
                for kk in 0..D {
                    for l in 0..D {
                        let mut s = 0.0;
                        for j in 0..D {
                            s += ga[j] * a[(D * i + j, D * kk + l)];
                        }
                        c[kk][l] = s * w;
                    }
                }
                let inertia = -rw2 * tg[a_] * w;
                for b in 0..N {
                    let gb = &pt.g[b];
                    for kk in 0..D {
                        let mut s = 0.0;
                        for l in 0..D {
                            s += c[kk][l] * gb[l];
                        }
                        if kk == i {
                            s += inertia * tg[b];
                        }
                        k[row + D * b + kk] += s;
                    }
                }
            }
        }
    }
    if has_p && with_k {
        if exact {
            for row in 0..nu {
                for m in 0..np {
                    k[row * nd + nu + m] += kup[row][m];
                    k[(nu + m) * nd + row] += kup[row][m];
                }
            }
        } else {
            for row in 0..nu {
                let mut km = [0.0; 4];
                for n in 0..np {
                    km[n] = kappa * (0..np).map(|m| kup[row][m] * minv[(m, n)]).sum::<f64>();
                }
                for s in 0..nu {
                    k[row * nd + s] += (0..np).map(|n| km[n] * kup[s][n]).sum::<f64>();
                }
            }
        }
    }
    Ok(())
}

/// Strain energy ∫ W(F) dV of a cell (compressible laws; the pressure terms are not included).
pub fn cell_energy<T, M, const D: usize, const N: usize>(
    pts: &[Point<D, N>],
    u: &[f64],
    material: &M,
) -> f64
where
    T: InvariantTensor,
    M: Hyperelastic<T> + ?Sized,
{
    pts.iter()
        .map(|p| material.energy(&grad_u::<T, D, N>(u, &p.g)) * p.w)
        .sum()
}

/// The strain-rate damping of one cell, added to `r` (the first D·N rows) and, unless `k` is
/// empty, to its tangent `k` (row-major with row length `nd` ≥ D·N): the viscous second
/// Piola–Kirchhoff stress S_v = η Ė on the Green-strain rate Ė = ½ (Ḟᵀ F + Fᵀ Ḟ), Ḟ = ∇v,
/// as the first Piola–Kirchhoff stress F S_v (objective: a rigid rotation has Ė = 0). `u` and
/// `v` hold the cell's nodal displacements and velocities (D·N, node-major); a unit change of
/// the unknown moves v by `kv` (the tangent holds ∂/∂u + kv ∂/∂v).
#[allow(clippy::too_many_arguments)]
pub fn viscous_cell<const D: usize, const N: usize>(
    pts: &[Point<D, N>],
    u: &[f64],
    v: &[f64],
    eta: f64,
    kv: f64,
    nd: usize,
    r: &mut [f64],
    k: &mut [f64],
) {
    viscous_cell_scaled::<D, N>(pts, u, v, eta, 1.0, kv, nd, r, k);
}

/// [`viscous_cell`] with the tangent kx ∂/∂u + kv ∂/∂v: `kx = 1, kv = 0` gives the
/// derivative in the displacements at fixed nodal velocities, `kx = 0, kv = 1` the one in the
/// velocities (the steady mode, whose velocities are ring differences of the displacements,
/// combines the two).
#[allow(clippy::needless_range_loop, clippy::too_many_arguments)]
pub fn viscous_cell_scaled<const D: usize, const N: usize>(
    pts: &[Point<D, N>],
    u: &[f64],
    v: &[f64],
    eta: f64,
    kx: f64,
    kv: f64,
    nd: usize,
    r: &mut [f64],
    k: &mut [f64],
) {
    let with_k = !k.is_empty();
    for pt in pts {
        let (mut f, mut fd) = ([[0.0; D]; D], [[0.0; D]; D]);
        for i in 0..D {
            f[i][i] = 1.0;
            for b in 0..N {
                for j in 0..D {
                    f[i][j] += u[D * b + i] * pt.g[b][j];
                    fd[i][j] += v[D * b + i] * pt.g[b][j];
                }
            }
        }
        let mut s = [[0.0; D]; D];
        for i in 0..D {
            for j in 0..D {
                let e: f64 = (0..D)
                    .map(|m| fd[m][i] * f[m][j] + f[m][i] * fd[m][j])
                    .sum();
                s[i][j] = 0.5 * eta * e;
            }
        }
        let mut p = [[0.0; D]; D];
        for i in 0..D {
            for j in 0..D {
                p[i][j] = (0..D).map(|m| f[i][m] * s[m][j]).sum();
            }
        }
        let w = pt.w;
        for a in 0..N {
            for i in 0..D {
                let ri: f64 = (0..D).map(|j| p[i][j] * pt.g[a][j]).sum();
                r[D * a + i] += ri * w;
            }
        }
        if !with_k {
            continue;
        }
        for b in 0..N {
            let gb = &pt.g[b];
            // S g_b (for δF S with δF = e_c ⊗ g_b).
            let mut sg = [0.0; D];
            for j in 0..D {
                sg[j] = (0..D).map(|m| gb[m] * s[m][j]).sum();
            }
            for c in 0..D {
                // δĖ = ½ (g_b ⊗ Ḟ_c + Ḟ_c ⊗ g_b) + ½ kv (g_b ⊗ F_c + F_c ⊗ g_b), with Ḟ_c and
                // F_c the c-th rows of Ḟ and F.
                let mut ds = [[0.0; D]; D];
                for i in 0..D {
                    for j in 0..D {
                        let de = kx * (gb[i] * fd[c][j] + fd[c][i] * gb[j])
                            + kv * (gb[i] * f[c][j] + f[c][i] * gb[j]);
                        ds[i][j] = 0.5 * eta * de;
                    }
                }
                for a in 0..N {
                    let ga = &pt.g[a];
                    for i in 0..D {
                        // δP_iJ = δ_ic (S g_b)_J + Σ_K F_iK δS_KJ.
                        let mut kij = 0.0;
                        for j in 0..D {
                            let mut dp: f64 = (0..D).map(|m| f[i][m] * ds[m][j]).sum();
                            if i == c {
                                dp += kx * sg[j];
                            }
                            kij += dp * ga[j];
                        }
                        k[(D * a + i) * nd + D * b + c] += kij * w;
                    }
                }
            }
        }
    }
}
