//! Steady rolling with a viscoelastic material: the internal variables integrated along the
//! streamlines (exactly along closed rings of quadrature points, or by an upwind scheme on any
//! mesh), and the streamline coupling of the consistent tangent.
//!
//! # Equations
//!
//! In steady rolling at angular speed ω the history of a material point is the spatial history
//! along its reference circle (θ = Θ + ω t). Both models of [`crate::material::viscoelastic`]
//! have internal variables obeying a linear ODE; along a ring it reads
//!
//! ```text
//! ω ∂θX + X/τ_i = f_i(E, ω ∂θE),        X(θ + 2π) = X(θ)
//! ```
//!
//! (convolution: `X = Q_i`, `f = g_i ω ∂θE`; multiplicative: `X = E_v,i`, `f = E/τ_i`). On the
//! built-in annulus the quadrature points with the same radial Gauss index in one radial layer
//! of cells lie on one circle; in flow order (counter-clockwise for ω > 0) they form a ring
//! `k = 0 … m−1` with angular spacings `Δθ_k`. With `E` linear in θ between successive points
//! the exponential step is exact (`Δt_k = Δθ_k / |ω|`, `a_k = exp(−Δt_k/τ_i)`,
//! `φ_k = (1 − a_k) τ_i/Δt_k`):
//!
//! ```text
//! convolution:     X_{k+1} = a_k X_k + g_i φ_k (E_{k+1} − E_k)
//! multiplicative:  X_{k+1} = a_k X_k + (φ_k − a_k) E_k + (1 − φ_k) E_{k+1}
//! ```
//!
//! a cyclic affine recurrence whose periodic solution is obtained in closed form
//! ([`crate::material::viscoelastic_ring::periodic_affine`]: one sweep from zero, the wrap-around
//! factor `(1 − Π a_k)⁻¹ = (1 − e^{−2π/(|ω| τ_i)})⁻¹`, a second sweep). No start-up, no truncated
//! memory. The stress at a point is then the overstress of the material from that state
//! ([`crate::material::Viscoelastic::overstress`] with Δt = 0); `ω = 0` gives the relaxed state.
//!
//! **Components.** The internal variables are tensors on the material (reference)
//! configuration, and in the θ-referential description the material that is at angle θ now was
//! at θ − ω s a time s ago, rotated by −ω s with the body. The ODE above therefore holds for the
//! components in the co-rotating polar basis (e_r, e_θ) at each point (`E_rr, E_θθ, E_rθ`), not
//! for the Cartesian ones: the Cartesian form would have the extra spin terms
//! `ω (WX − XW)` (`W` the unit skew tensor). The strains are rotated to the polar basis of
//! their point, the ring is integrated, and the internal variables are rotated back. (Without
//! it the power of the hub torque missed the viscous dissipation by 30 % on every mesh.)
//!
//! # Tangent
//!
//! `X = L_i E` is linear in the ring's strains (a dense ring operator: a point depends on every
//! point upstream, with a kernel decaying like `exp(−Δθ/(|ω|τ_i))`). The element kernels
//! assemble the tangent with the state *frozen* plus, for the convolution model, the
//! instantaneous response `γ Σ g_i` (the kernel's Δt = 0 overstress). The rest of the exact
//! tangent,
//!
//! ```text
//! δP = F δS,   convolution:     δS = γ Σ_i (L_i − g_i) δE
//!              multiplicative:  δS = Σ_i −2 μ_i C_v,i⁻¹ (L_i δE) C_v,i⁻¹,      δE = sym(Fᵀ ∇δu)
//! ```
//!
//! is never assembled: [`SteadyHistory::apply_correction`] applies it to a vector in O(number of
//! points) with the same two ring sweeps, and Newton solves with the exact tangent by GMRES
//! preconditioned with the factorization of the assembled (sparse) part
//! ([`crate::solver::newton`]). The sparsity pattern and the direct solver's fill are those of the
//! elastic problem.
//!
//! # Meshes without rings
//!
//! Gmsh meshes, adaptively refined meshes (hanging nodes) and meshes of mixed degree have no
//! closed rings of points. There the same ODE, written for `Y = X − g E` (convolution) or
//! `Y = X` (multiplicative) as the transport–reaction equation `β·∇Y + Y/τ_i = s(E)` with the
//! rigid rotation field `β = ω (−X₂, X₁)` and a source without derivatives
//! (`s = −g E/τ_i` or `E/τ_i`), is discretised by upwind discontinuous Galerkin on the
//! quadrature points ([`crate::physics::streamline_upwind`]): order q = degree + 1 at the
//! points on any mesh, exact for constants. `X = L_i E` is again linear in the strains, so the
//! tangent correction above applies unchanged, with `L_i` a sparse solve instead of the ring
//! sweeps. [`StreamlineScheme`] chooses (`[solver] steady_history`): `Auto` takes the rings
//! where the mesh has them.
//!
//! Units: those of the scene (stress for γ, time for τ_i, rad/s for ω).

use super::streamline_upwind::{UpwindError, UpwindTransport};
use super::SolidModel;
use crate::assembly::{DofMap, QpHistory, CONSTRAINED};
use crate::material::viscoelastic::{green_strain, ViscoModel, Viscoelastic};
use crate::material::viscoelastic_ring::{sweep_ring, RingScratch};
use crate::math::{Mat2, Vec2};

/// How the steady internal variables are integrated along the streamlines.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum StreamlineScheme {
    /// Exact rings where the mesh has them (the generated annulus), upwind otherwise.
    #[default]
    Auto,
    /// Exact integration along closed rings of quadrature points (ring-structured meshes).
    Rings,
    /// Upwind discontinuous Galerkin on the quadrature points ([`UpwindTransport`]): any mesh.
    Upwind,
}

impl StreamlineScheme {
    /// The scheme's keyword (`"auto"`, `"rings"`, `"upwind"`).
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Rings => "rings",
            Self::Upwind => "upwind",
        }
    }
}

/// Why a mesh cannot carry the steady viscoelastic history.
#[derive(Clone, Debug, PartialEq)]
pub enum StreamlineError {
    /// Rings were asked for on a mesh without ring structure (e.g. a Gmsh mesh).
    NoRings,
    /// Rings were asked for on cells of different polynomial degree (different Gauss rules).
    MixedDegree,
    /// The points of a ring do not lie on one circle or do not go once around it.
    NotACircle { ring: usize },
    /// The upwind operator could not be built.
    Upwind(UpwindError),
}

impl std::fmt::Display for StreamlineError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NoRings => write!(
                f,
                "the \"rings\" streamline scheme integrates the viscoelastic internal variables \
                 exactly along closed rings of quadrature points, which needs the ring-structured \
                 generated annulus; this mesh (mesh.file or a refined mesh) has no rings. Use \
                 [solver] steady_history = \"upwind\" (or \"auto\")"
            ),
            Self::MixedDegree => write!(
                f,
                "the \"rings\" streamline scheme needs cells of one polynomial degree; use \
                 [solver] steady_history = \"upwind\" (or \"auto\")"
            ),
            Self::NotACircle { ring } => write!(
                f,
                "the quadrature points of ring {ring} do not lie on one circle in order: the \
                 \"rings\" streamline scheme needs the generated annulus; use [solver] \
                 steady_history = \"upwind\" (or \"auto\")"
            ),
            Self::Upwind(e) => write!(f, "upwind streamline scheme: {e}"),
        }
    }
}

/// Per quadrature point: weight and reference shape gradients.
#[derive(Clone, Copy, Debug)]
struct QpGeo {
    w: f64,
    g: [[f64; 2]; 9],
}

/// The closed rings of quadrature points of a ring-structured mesh.
#[derive(Clone, Debug)]
struct Rings {
    /// Points of each ring, counter-clockwise, as global point indices (history order).
    rings: Vec<Vec<u32>>,
    /// Angle from point k to point k + 1 of each ring (counter-clockwise; the last wraps).
    dtheta: Vec<Vec<f64>>,
    /// Largest relative deviation of a ring's points from its first point's radius.
    radius_deviation: f64,
    /// Ring scratch.
    scratch: RingScratch,
}

/// The discretisation of the streamline ODE.
#[derive(Clone, Debug)]
enum Streamlines {
    Rings(Rings),
    Upwind(Box<UpwindTransport>),
}

/// The steady viscoelastic history of a model (see the module docs).
#[derive(Clone, Debug)]
pub struct SteadyHistory {
    streamlines: Streamlines,
    /// Nodes of each cell.
    nn: Vec<u8>,
    /// Cell of each global point.
    cell_of: Vec<u32>,
    geo: Vec<QpGeo>,
    /// Deformation gradient at each point at the last [`Self::sync`].
    f: Vec<Mat2>,
    /// Green strain (or its variation) per point: scratch.
    e: Vec<[f64; 3]>,
    /// Overstress variation per point: scratch.
    ds: Vec<Mat2>,
    /// Strain variation per point in Cartesian components: scratch.
    de: Vec<[f64; 3]>,
    /// (cos φ, sin φ) of each point's polar angle φ (the polar basis e_r, e_θ).
    rot: Vec<(f64, f64)>,
    /// Per-point scratch of the upwind solves.
    rhs: Vec<f64>,
    /// Full-length scratch for a vector in equation numbering expanded to full dofs.
    full: Vec<f64>,
    /// Ring-operator output per point, term and component: scratch.
    dxs: Vec<f64>,
}

/// Components `[a_rr, a_θθ, a_rθ]` in the polar basis at angle φ (`rot` = (cos φ, sin φ))
/// of the symmetric tensor with Cartesian components `[a11, a22, a12]`: `Rᵀ A R`.
#[inline]
fn to_polar(a: [f64; 3], rot: (f64, f64)) -> [f64; 3] {
    let (c, s) = rot;
    [
        c * c * a[0] + 2.0 * c * s * a[2] + s * s * a[1],
        s * s * a[0] - 2.0 * c * s * a[2] + c * c * a[1],
        c * s * (a[1] - a[0]) + (c * c - s * s) * a[2],
    ]
}

/// The inverse of [`to_polar`]: `R P Rᵀ`.
#[inline]
fn from_polar(p: [f64; 3], rot: (f64, f64)) -> [f64; 3] {
    to_polar(p, (rot.0, -rot.1))
}

impl Rings {
    /// The rings of quadrature points of `model` (point positions `pos`), or why it has none.
    fn new(model: &SolidModel, pos: &[Vec2]) -> Result<Self, StreamlineError> {
        let mesh = &model.mesh;
        let layout = mesh.rings.as_ref().ok_or(StreamlineError::NoRings)?;
        let deg = mesh.degree.first().copied().unwrap_or(2);
        if mesh.degree.iter().any(|&d| d != deg) {
            return Err(StreamlineError::MixedDegree);
        }
        let nc = mesh.n_cells();
        if nc == 0 || layout.n_r * layout.n_theta != nc {
            return Err(StreamlineError::NoRings);
        }
        let q = model.qp_per_direction(0);
        let hist = &model.history;
        if hist.offsets.len() != nc + 1 || (0..nc).any(|c| hist.points_in_cell(c) != q * q) {
            return Err(StreamlineError::NoRings);
        }
        let n_rings = QpHistory::n_rings(layout, q);
        let mut rings = Vec::with_capacity(n_rings);
        let mut dtheta = Vec::with_capacity(n_rings);
        let mut dev = 0.0f64;
        for r in 0..n_rings {
            let pts: Vec<u32> = QpHistory::ring(layout, q, r)
                .map(|(c, p)| (hist.offsets[c] + p) as u32)
                .collect();
            let m = pts.len();
            let r0 = pos[pts[0] as usize].norm();
            let mut d = Vec::with_capacity(m);
            let mut total = 0.0;
            for k in 0..m {
                let (a, b) = (pos[pts[k] as usize], pos[pts[(k + 1) % m] as usize]);
                // Isoparametric cells place the points on the interpolated arc, within
                // O(h⁴) of the circle (measured 4e-4 r with 8 Q2 cells around, 2e-6 r with
                // 32): the ring is then the interpolated streamline. A tolerance far above
                // that and below a cell size tells a ring mesh from anything else.
                dev = dev.max((b.norm() - r0).abs() / r0);
                if (b.norm() - r0).abs() > 1e-2 * r0 {
                    return Err(StreamlineError::NotACircle { ring: r });
                }
                let mut t = b[1].atan2(b[0]) - a[1].atan2(a[0]);
                if t <= 0.0 {
                    t += 2.0 * std::f64::consts::PI;
                }
                total += t;
                d.push(t);
            }
            if (total - 2.0 * std::f64::consts::PI).abs() > 1e-9 {
                return Err(StreamlineError::NotACircle { ring: r });
            }
            rings.push(pts);
            dtheta.push(d);
        }
        Ok(Self {
            rings,
            dtheta,
            radius_deviation: dev,
            scratch: RingScratch::default(),
        })
    }

    /// For each ring, Prony term and strain component, the periodic solution `X = L_i e` of
    /// the exact step recurrence driven by the per-point strains `e`, handed to
    /// `out(point, term, component, X)`.
    fn sweep(
        &mut self,
        e: &[[f64; 3]],
        ve: &Viscoelastic,
        omega: f64,
        out: &mut impl FnMut(usize, usize, usize, f64),
    ) {
        for (pts, dth) in self.rings.iter().zip(&self.dtheta) {
            sweep_ring(
                pts,
                dth,
                ve,
                omega,
                3,
                |p, c| e[p][c],
                out,
                &mut self.scratch,
            );
        }
    }
}

impl SteadyHistory {
    /// The streamlines of the quadrature points of `model` (which must be viscoelastic, with
    /// its history allocated by [`SolidModel::set_viscoelastic`]), discretised by `scheme`.
    pub fn new(model: &SolidModel, scheme: StreamlineScheme) -> Result<Self, StreamlineError> {
        let mesh = &model.mesh;
        let nc = mesh.n_cells();
        let hist = &model.history;
        let n_pts = hist.offsets.last().copied().unwrap_or(0);
        let degenerate = |cell| StreamlineError::Upwind(UpwindError::Degenerate { cell });
        let mut geo = vec![
            QpGeo {
                w: 0.0,
                g: [[0.0; 2]; 9]
            };
            n_pts
        ];
        let mut pos = vec![Vec2::zeros(); n_pts];
        let mut cell_of = vec![0u32; n_pts];
        for c in 0..nc {
            let q = model.qp_per_direction(c);
            if hist.points_in_cell(c) != q * q {
                return Err(StreamlineError::Upwind(UpwindError::NotTensorGauss {
                    cell: c,
                    points: hist.points_in_cell(c),
                }));
            }
            for p in 0..q * q {
                let i = hist.offsets[c] + p;
                let mut g = [[0.0; 2]; 9];
                let (x, w) = model.qp_geometry(c, p, &mut g).ok_or(degenerate(c))?;
                geo[i] = QpGeo { w, g };
                pos[i] = x;
                cell_of[i] = c as u32;
            }
        }
        let upwind = || -> Result<Streamlines, StreamlineError> {
            let op =
                UpwindTransport::new(mesh, &hist.offsets, true).map_err(StreamlineError::Upwind)?;
            Ok(Streamlines::Upwind(Box::new(op)))
        };
        let streamlines = match scheme {
            StreamlineScheme::Rings => Streamlines::Rings(Rings::new(model, &pos)?),
            StreamlineScheme::Upwind => upwind()?,
            StreamlineScheme::Auto => match Rings::new(model, &pos) {
                Ok(r) => Streamlines::Rings(r),
                Err(_) => upwind()?,
            },
        };
        Ok(Self {
            streamlines,
            nn: (0..nc).map(|c| mesh.cell_nodes(c).len() as u8).collect(),
            cell_of,
            geo,
            f: vec![Mat2::identity(); n_pts],
            e: vec![[0.0; 3]; n_pts],
            ds: vec![Mat2::zeros(); n_pts],
            de: vec![[0.0; 3]; n_pts],
            rot: pos
                .iter()
                .map(|x| {
                    let r = x.norm();
                    (x[0] / r, x[1] / r)
                })
                .collect(),
            rhs: Vec::new(),
            full: Vec::new(),
            dxs: Vec::new(),
        })
    }

    /// The scheme in use: [`StreamlineScheme::Rings`] or [`StreamlineScheme::Upwind`].
    pub fn scheme(&self) -> StreamlineScheme {
        match self.streamlines {
            Streamlines::Rings(_) => StreamlineScheme::Rings,
            Streamlines::Upwind(_) => StreamlineScheme::Upwind,
        }
    }

    /// Largest relative deviation of a ring's points from its first point's radius (0 for the
    /// upwind scheme).
    pub fn radius_deviation(&self) -> f64 {
        match &self.streamlines {
            Streamlines::Rings(r) => r.radius_deviation,
            Streamlines::Upwind(_) => 0.0,
        }
    }

    /// The upwind operator, when that scheme is in use.
    pub fn upwind(&self) -> Option<&UpwindTransport> {
        match &self.streamlines {
            Streamlines::Upwind(op) => Some(op),
            Streamlines::Rings(_) => None,
        }
    }

    /// Dissipation rate `∫ D dV` of the multiplicative model over the body at the state of
    /// the last [`Self::sync`] (power per unit thickness; `None` for the convolution model,
    /// which has no free energy). In steady rolling without other dissipation it balances
    /// the power of the hub torque, `T ω`.
    pub fn dissipation(&self, model: &SolidModel) -> Option<f64> {
        let ve = model.viscoelastic?;
        let ns = model.history.n_state;
        let mut d = 0.0;
        for (i, (geo, f)) in self.geo.iter().zip(&self.f).enumerate() {
            let h = f - Mat2::identity();
            d += geo.w * ve.dissipation_rate(&h, &model.history.data[i * ns..(i + 1) * ns])?;
        }
        Some(d)
    }

    /// Number of rings (0 for the upwind scheme).
    pub fn n_rings(&self) -> usize {
        match &self.streamlines {
            Streamlines::Rings(r) => r.rings.len(),
            Streamlines::Upwind(_) => 0,
        }
    }

    /// Global point indices of ring `r`, counter-clockwise (the rings scheme only).
    pub fn ring_points(&self, r: usize) -> &[u32] {
        match &self.streamlines {
            Streamlines::Rings(rings) => &rings.rings[r],
            Streamlines::Upwind(_) => &[],
        }
    }

    /// ∇u at every point of the model from the full state `x` into `self.f` (as F = I + ∇u).
    fn deformation(&mut self, dofs: &DofMap, x: &[f64]) {
        for (i, (geo, f)) in self.geo.iter().zip(self.f.iter_mut()).enumerate() {
            let c = self.cell_of[i] as usize;
            let nn = usize::from(self.nn[c]);
            let cd = dofs.cell(c);
            let mut h = Mat2::zeros();
            for a in 0..nn {
                let (ux, uy) = (x[cd[2 * a] as usize], x[cd[2 * a + 1] as usize]);
                h[(0, 0)] += ux * geo.g[a][0];
                h[(0, 1)] += ux * geo.g[a][1];
                h[(1, 0)] += uy * geo.g[a][0];
                h[(1, 1)] += uy * geo.g[a][1];
            }
            *f = Mat2::identity() + h;
        }
    }

    /// For each Prony term and strain component, `X = L_i e` along the streamlines for the
    /// per-point polar strains in `self.e`, handed to `out(point, term, component, X)`. A
    /// failed upwind factorisation gives NaN (the residual then tells Newton).
    fn sweep(
        &mut self,
        model: &SolidModel,
        ve: &Viscoelastic,
        omega: f64,
        mut out: impl FnMut(usize, usize, usize, f64),
    ) {
        let op = match &mut self.streamlines {
            Streamlines::Rings(r) => return r.sweep(&self.e, ve, omega, &mut out),
            Streamlines::Upwind(op) => op,
        };
        if op.forward() != (omega >= 0.0) {
            match UpwindTransport::new(&model.mesh, &model.history.offsets, omega >= 0.0) {
                Ok(o) => **op = o,
                Err(_) => {
                    return (0..self.e.len()).for_each(|p| {
                        (0..ve.prony().len())
                            .for_each(|i| (0..3).for_each(|c| out(p, i, c, f64::NAN)))
                    })
                }
            }
        }
        let taus: Vec<f64> = ve.prony().iter().map(|&(_, tau)| tau).collect();
        let n = self.e.len();
        for (i, &(g, tau)) in ve.prony().iter().enumerate() {
            for comp in 0..3 {
                // β·∇Y + Y/τ = s: convolution X = g E + Y with s = −g E/τ; multiplicative
                // X = Y with s = E/τ.
                let scale = match ve.model {
                    ViscoModel::Convolution => -g / tau,
                    ViscoModel::Multiplicative => 1.0 / tau,
                };
                self.rhs.clear();
                self.rhs.extend(self.e.iter().map(|e| scale * e[comp]));
                if op.solve(omega, &taus, i, &mut self.rhs).is_err() {
                    self.rhs.iter_mut().for_each(|v| *v = f64::NAN);
                }
                for p in 0..n {
                    let x = match ve.model {
                        ViscoModel::Convolution => g * self.e[p][comp] + self.rhs[p],
                        ViscoModel::Multiplicative => self.rhs[p],
                    };
                    out(p, i, comp, x);
                }
            }
        }
    }

    /// Replace the history of `model` by the periodic steady states of the full state `x` at
    /// angular speed `omega` (ω ∂θ along the rings; ω = 0: relaxed). Call before every
    /// evaluation of the residual; the kernels then evaluate the overstress with Δt = 0.
    pub fn sync(&mut self, model: &mut SolidModel, dofs: &DofMap, x: &[f64], omega: f64) {
        let Some(ve) = model.viscoelastic else {
            return;
        };
        model.history_dt = 0.0;
        self.deformation(dofs, x);
        for (e, f) in self.e.iter_mut().zip(&self.f) {
            let g = green_strain(&(f - Mat2::identity()));
            *e = [g[(0, 0)], g[(1, 1)], 0.5 * (g[(0, 1)] + g[(1, 0)])];
        }
        let ns = model.history.n_state;
        for (i, e) in self.e.iter_mut().enumerate() {
            model.history.data[i * ns..i * ns + 3].copy_from_slice(e);
            // The streamline ODE holds for polar components (see the module docs).
            *e = to_polar(*e, self.rot[i]);
        }
        let mut xs = std::mem::take(&mut self.dxs);
        let n_terms = ve.prony().len();
        xs.resize(self.e.len() * 3 * n_terms, 0.0);
        self.sweep(model, &ve, omega, |pt, term, comp, v| {
            xs[(pt * n_terms + term) * 3 + comp] = v;
        });
        let data = &mut model.history.data;
        for (pt, rot) in self.rot.iter().enumerate() {
            for term in 0..n_terms {
                let o = (pt * n_terms + term) * 3;
                let xc = from_polar([xs[o], xs[o + 1], xs[o + 2]], *rot);
                data[pt * ns + 3 + 3 * term..pt * ns + 6 + 3 * term].copy_from_slice(&xc);
            }
        }
        self.dxs = xs;
    }

    /// `out += (K − K_kernels) v`: the part of the exact steady tangent that the element
    /// kernels do not assemble (see the module docs), for `v` and `out` in equation numbering,
    /// at the state of the last [`Self::sync`].
    pub fn apply_correction(
        &mut self,
        model: &SolidModel,
        dofs: &DofMap,
        omega: f64,
        v: &[f64],
        out: &mut [f64],
    ) {
        let Some(ve) = model.viscoelastic else {
            return;
        };
        let n_full = dofs.eq.len();
        let mut full = std::mem::take(&mut self.full);
        full.clear();
        full.resize(n_full, 0.0);
        // Hanging-node values from their masters.
        dofs.scatter_free(v, &mut full);
        // δE = sym(Fᵀ ∇δu) per point.
        for (i, geo) in self.geo.iter().enumerate() {
            let c = self.cell_of[i] as usize;
            let nn = usize::from(self.nn[c]);
            let cd = dofs.cell(c);
            let mut dh = Mat2::zeros();
            for a in 0..nn {
                let (ux, uy) = (full[cd[2 * a] as usize], full[cd[2 * a + 1] as usize]);
                dh[(0, 0)] += ux * geo.g[a][0];
                dh[(0, 1)] += ux * geo.g[a][1];
                dh[(1, 0)] += uy * geo.g[a][0];
                dh[(1, 1)] += uy * geo.g[a][1];
            }
            let f = self.f[i];
            let de = (f.transpose() * dh + dh.transpose() * f) * 0.5;
            self.de[i] = [de[(0, 0)], de[(1, 1)], 0.5 * (de[(0, 1)] + de[(1, 0)])];
            self.e[i] = to_polar(self.de[i], self.rot[i]);
        }
        for d in self.ds.iter_mut() {
            *d = Mat2::zeros();
        }
        let ns = model.history.n_state;
        let state = &model.history.data;
        // δX per point, term and component (then δS).
        let n_terms = ve.prony().len();
        let mut dxs = std::mem::take(&mut self.dxs);
        dxs.resize(self.e.len() * 3 * n_terms, 0.0);
        self.sweep(model, &ve, omega, |pt, term, comp, val| {
            dxs[(pt * n_terms + term) * 3 + comp] = val;
        });
        for (pt, ds) in self.ds.iter_mut().enumerate() {
            for (i, &(g, _)) in ve.prony().iter().enumerate() {
                let o = (pt * n_terms + i) * 3;
                let x = from_polar([dxs[o], dxs[o + 1], dxs[o + 2]], self.rot[pt]);
                let dxi = Mat2::new(x[0], x[2], x[2], x[1]);
                match ve.model {
                    ViscoModel::Convolution => {
                        let de = &self.de[pt];
                        let dei = Mat2::new(de[0], de[2], de[2], de[1]);
                        *ds += (dxi - dei * g) * ve.gamma;
                    }
                    ViscoModel::Multiplicative => {
                        let mu = 0.5 * ve.gamma * g;
                        let s = &state[pt * ns + 3 + 3 * i..pt * ns + 6 + 3 * i];
                        let cv = Mat2::identity() + Mat2::new(s[0], s[2], s[2], s[1]) * 2.0;
                        let gi = cv.try_inverse().unwrap_or(Mat2::zeros());
                        *ds -= gi * dxi * gi * (2.0 * mu);
                    }
                }
            }
        }
        self.dxs = dxs;
        // out_{a i} += Σ_q w (F δS)_{iJ} ∂N_a/∂X_J.
        for (i, geo) in self.geo.iter().enumerate() {
            let dp = self.f[i] * self.ds[i];
            let c = self.cell_of[i] as usize;
            let nn = usize::from(self.nn[c]);
            let cd = dofs.cell(c);
            for a in 0..nn {
                for comp in 0..2 {
                    let d = cd[2 * a + comp];
                    let q = dofs.eq[d as usize];
                    let y = geo.w * (dp[(comp, 0)] * geo.g[a][0] + dp[(comp, 1)] * geo.g[a][1]);
                    if q < CONSTRAINED {
                        out[q as usize] += y;
                    } else {
                        // A hanging node's row goes to its free masters with their weights.
                        for &(m, w) in dofs.expansion(d).unwrap_or(&[]) {
                            let em = dofs.eq[m as usize];
                            if em < CONSTRAINED {
                                out[em as usize] += w * y;
                            }
                        }
                    }
                }
            }
        }
        self.full = full;
    }
}
