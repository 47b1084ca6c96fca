//! A posteriori error estimators for the finite-strain solid at a converged state.
//!
//! **Error measure.** The error of a converged finite element state u_h is measured in the
//! energy norm of the problem linearised about it,
//!
//! ```text
//! ‖e‖²_A = Σ_K ∫_K ∇e : A(F_h) : ∇e dX,     e = u − u_h,   A = ∂P/∂F at F_h = I + ∇u_h,
//! ```
//!
//! with A the tangent of the cell's law (including the pressure term −p ∂cof F/∂F of a mixed
//! formulation), per unit thickness, in the scene's energy unit. Where A is not positive (a
//! loss of ellipticity) a cell's quadratic form is clamped at 0. [`energy_error`] evaluates
//! ‖e‖_A cell by cell for a known exact gradient (manufactured or closed-form solutions): the
//! reference the estimators' effectivity index η / ‖e‖_A is measured against.
//!
//! The estimators return one indicator per cell and the global estimate η = (Σ η_K²)^{1/2}
//! ([`CellEstimate`]); behind the interface shared with the model problems
//! ([`crate::adapt::marking::CellEstimator`] of a [`SolidContext`]) they are [`Recovery`],
//! [`Interpolation`], [`ExplicitResidual`] and [`super::equilibrated::Equilibrated`]. Both vanish when u_h is exact: a homogeneous deformation (which Q1 and Q2
//! represent exactly) has no residual, no traction jump and is recovered exactly.
//!
//! * [`recovery`] (Zienkiewicz–Zhu): the displacement gradient H_h = ∇u_h is sampled at the
//!   superconvergent points of every cell and recovered at the nodes by the patch recovery of
//!   [`super::recovery`] (the same least-squares patch fits as the recovered stresses); the
//!   recovered field H* is interpolated by each cell's shape functions and
//!   η_K² = ∫_K (H* − H_h) : A : (H* − H_h). Asymptotically exact for smooth solutions.
//! * [`explicit_residual`]: with the first Piola–Kirchhoff stress P_h of the state,
//!
//!   ```text
//!   η_K² = (1/μ_K) [ (h_K/p_K)² ‖Div P_h + b − ρ ω² ∂θθχ_h‖²_K
//!                    + ½ Σ_{interior F ⊂ ∂K} (h_F/p_K) ‖[P_h N]‖²_F
//!                    + Σ_{free F ⊂ ∂K} (h_F/p_K) ‖P_h N‖²_F
//!                    + Σ_{contact F ⊂ ∂K} (h_F/p_K) ‖t_c − P_h N‖²_F ],
//!   ```
//!
//!   μ_K the small-strain shear modulus of the cell's law, h_K the cell's diameter, h_F the
//!   face's length, b the model's body force and ω² its spin (`SolidModel::omega2`, the
//!   θ-referential inertia, χ = X + u). "Free" faces are those of the named traction-free facet
//!   sets (e.g. the outer surface of a body without contact); faces on no named set and not
//!   shared by two cells (the hub) carry a displacement condition and no term. On contact
//!   facets ([`BoundaryTractions`]) the residual is the contact traction t_c (per reference
//!   length, at the contact rule's points) minus P_h N. The unknown
//!   constant of the estimate is taken as 1, so η is an error *indicator* whose ratio to the
//!   error stays bounded under refinement. Div P_h and ∂θθχ_h are evaluated by central
//!   differences (step 1e-4 of the reference cell) of the exact element fields.
//!
//! * [`interpolation`] (the interpolation estimator, with derivatives from the recovered
//!   gradient): the cell's error is modelled as the interpolation error of its degree-p
//!   Lagrange interpolant in each reference direction d,
//!   η_K² = c_p 2^{2p} Σ_d ∫_K (G_d ⊗ n_d) : A : (G_d ⊗ n_d) dX, with G_d = ∂_{ξ_d}^{p+1} u
//!   taken as ∂_{ξ_d}^p (H* ∂X/∂ξ_d) (H* the recovered gradient, central differences),
//!   n_d = ∇ξ_d and c_p = ∫_0^1 (ω′)² (c_1 = 1/12, c_2 = 1/720; see
//!   [`crate::adapt::estimate::interpolation_constant`]). On an axis-aligned square of side h
//!   it is the scalar estimator's c_p h^{2p} ‖∂^{p+1} u‖², per component. Degrees 1 and 2.
//!
//! Scope: the elastic stress of the state. The strain-rate damping and the viscous overstress of
//! the steady and transient modes are not part of the residual.

use super::recovery::{recover_nodal, sampling_points, CellSamples, Stress4};
use super::solid::{PressureMode, SolidModel};
use crate::adapt::marking::{CellEstimate, CellEstimator};
use crate::assembly::DofMap;
use crate::element::quadrature::gauss_1d;
use crate::material::invariants::dcof_df;
use crate::material::Hyperelastic as _;
use crate::math::{flatten, Mat2, Vec2};
use crate::mesh::locate::shape_values;
use crate::mesh::{Facet, Mesh};
use rayon::prelude::*;
use std::collections::HashMap;
use std::convert::Infallible;

/// What the solid's estimators need: the model, the state (`dofs`, full vector `x`), the
/// traction-free facet sets `free` and the tractions `applied` on boundary facets (the road's
/// contact; used by the residual estimators only).
#[derive(Clone, Copy)]
pub struct SolidContext<'a> {
    pub model: &'a SolidModel,
    pub dofs: &'a DofMap,
    pub x: &'a [f64],
    pub free: &'a [&'a str],
    pub applied: Option<&'a BoundaryTractions>,
}

/// The Zienkiewicz–Zhu recovery estimator ([`recovery`]) behind the shared interface.
pub struct Recovery;

/// The interpolation estimator with recovered derivatives ([`interpolation`]).
pub struct Interpolation;

/// The explicit residual estimator with the context's free sets and applied tractions
/// ([`explicit_residual_with`]).
pub struct ExplicitResidual;

impl CellEstimator<SolidContext<'_>> for Recovery {
    type Error = Infallible;
    fn name(&self) -> &'static str {
        "recovery (ZZ)"
    }
    fn estimate(&self, ctx: &SolidContext) -> Result<CellEstimate, Infallible> {
        Ok(recovery(ctx.model, ctx.dofs, ctx.x))
    }
}

impl CellEstimator<SolidContext<'_>> for Interpolation {
    type Error = Infallible;
    fn name(&self) -> &'static str {
        "interpolation (recovered derivatives)"
    }
    fn estimate(&self, ctx: &SolidContext) -> Result<CellEstimate, Infallible> {
        Ok(interpolation(ctx.model, ctx.dofs, ctx.x))
    }
}

impl CellEstimator<SolidContext<'_>> for ExplicitResidual {
    type Error = Infallible;
    fn name(&self) -> &'static str {
        "explicit residual"
    }
    fn estimate(&self, ctx: &SolidContext) -> Result<CellEstimate, Infallible> {
        Ok(explicit_residual_with(
            ctx.model,
            ctx.dofs,
            ctx.x,
            ctx.free,
            ctx.applied,
        ))
    }
}

/// Gauss points per direction of the error integrals on a degree-`p` cell.
fn error_rule(p: usize) -> usize {
    p + 3
}

/// Displacement gradient, first Piola–Kirchhoff stress, tangent A and geometry at (ξ, η).
pub(super) struct PointState {
    pub(super) x: Vec2,
    pub(super) h: Mat2,
    pub(super) p: Mat2,
    pub(super) jac: Mat2,
}

pub(super) fn point_state(
    model: &SolidModel,
    dofs: &DofMap,
    x: &[f64],
    c: usize,
    xi: f64,
    eta: f64,
) -> Option<PointState> {
    let pv = model.point_values(c, dofs, x, xi, eta)?;
    let f = Mat2::identity() + pv.grad_u;
    let j = f.determinant();
    let p = pv.sigma * j * f.try_inverse()?.transpose();
    Some(PointState {
        x: pv.x,
        h: pv.grad_u,
        p,
        jac: pv.jac,
    })
}

/// The quadratic form d : A : d of the linearised problem at the point state `s` of cell `c`.
fn energy_density(model: &SolidModel, c: usize, s: &PointState, d: &Mat2) -> f64 {
    let dv = flatten(d);
    dv.dot(&(tangent(model, c, s) * dv))
}

/// The tangent A = ∂P/∂F of the linearised problem at the point state `s` of cell `c`
/// (including −p ∂cof F/∂F of a mixed formulation), in the order of [`flatten`].
pub(super) fn tangent(model: &SolidModel, c: usize, s: &PointState) -> crate::math::Tangent {
    let law = model.material_of(c);
    let (p_law, mut a) = law.stress_tangent(&s.h);
    if !matches!(model.pressure, PressureMode::None) {
        // P = P_law − p cof F: p = tr((P_law − P) Fᵀ) / (2 J).
        let f = Mat2::identity() + s.h;
        let pres = ((p_law - s.p) * f.transpose()).trace() / (2.0 * f.determinant());
        a -= dcof_df() * pres;
    }
    a
}

/// Per-cell squares of the energy norm of `d(c, ξ, η, state)` over the error rule.
fn cell_energy<F>(model: &SolidModel, dofs: &DofMap, x: &[f64], d: F) -> Vec<f64>
where
    F: Fn(usize, f64, f64, &PointState) -> Option<Mat2> + Sync,
{
    (0..model.mesh.n_cells())
        .into_par_iter()
        .map(|c| {
            let (pts, wts) = gauss_1d(error_rule(model.mesh.degree[c] as usize));
            let mut sum = 0.0;
            for (l, &eta) in pts.iter().enumerate() {
                for (i, &xi) in pts.iter().enumerate() {
                    let Some(s) = point_state(model, dofs, x, c, xi, eta) else {
                        continue;
                    };
                    let Some(dm) = d(c, xi, eta, &s) else {
                        continue;
                    };
                    let w = wts[i] * wts[l] * s.jac.determinant().abs();
                    sum += w * energy_density(model, c, &s, &dm);
                }
            }
            sum
        })
        .collect()
}

/// ‖∇(u − u_h)‖_A per cell and in total, for the exact displacement gradient `exact(X)`.
pub fn energy_error(
    model: &SolidModel,
    dofs: &DofMap,
    x: &[f64],
    exact: &(dyn Fn(Vec2) -> Mat2 + Sync),
) -> CellEstimate {
    CellEstimate::from_squares(cell_energy(model, dofs, x, |_, _, _, s| {
        Some(exact(s.x) - s.h)
    }))
}

/// The energy norm ‖u_h‖_A of the state itself, ( Σ_K ∫ ∇u_h : A : ∇u_h )^{1/2}: the scale of
/// relative errors.
pub fn energy_norm(model: &SolidModel, dofs: &DofMap, x: &[f64]) -> f64 {
    cell_energy(model, dofs, x, |_, _, _, s| Some(s.h))
        .iter()
        .map(|v| v.max(0.0))
        .sum::<f64>()
        .sqrt()
}

/// Recovered nodal displacement gradient `[H11, H12, H21, H22]` (superconvergent patch
/// recovery of the samples at the superconvergent points).
pub fn recover_gradient(model: &SolidModel, dofs: &DofMap, x: &[f64]) -> Vec<Stress4> {
    let samples: Vec<CellSamples> = (0..model.mesh.n_cells())
        .into_par_iter()
        .map(|c| {
            let mut cs = CellSamples::default();
            for &(xi, eta) in sampling_points(model.mesh.degree[c] as usize) {
                if let Some(pv) = model.point_values(c, dofs, x, xi, eta) {
                    let h = pv.grad_u;
                    let s = [h[(0, 0)], h[(0, 1)], h[(1, 0)], h[(1, 1)]];
                    if s.iter().all(|v| v.is_finite()) {
                        cs.x[cs.n] = pv.x;
                        cs.s[cs.n] = s;
                        cs.n += 1;
                    }
                }
            }
            cs
        })
        .collect();
    recover_nodal(&model.mesh, &samples)
}

/// The recovered gradient `nodal` ([`recover_gradient`]) interpolated at (ξ, η) of cell `c`.
fn recovered_at(mesh: &Mesh, nodal: &[Stress4], c: usize, xi: f64, eta: f64) -> Mat2 {
    let mut n = [0.0; 9];
    shape_values(mesh, c, xi, eta, &mut n);
    let mut hs = Mat2::zeros();
    for (a, &node) in mesh.cell_nodes(c).iter().enumerate() {
        let g = nodal[node as usize];
        hs += Mat2::new(g[0], g[1], g[2], g[3]) * n[a];
    }
    hs
}

/// The Zienkiewicz–Zhu recovery estimator (see the module docs).
pub fn recovery(model: &SolidModel, dofs: &DofMap, x: &[f64]) -> CellEstimate {
    let nodal = recover_gradient(model, dofs, x);
    let mesh = &model.mesh;
    CellEstimate::from_squares(cell_energy(model, dofs, x, |c, xi, eta, s| {
        Some(recovered_at(mesh, &nodal, c, xi, eta) - s.h)
    }))
}

/// Corner nodes of a facet (its first and last node in the side's parameter order).
fn facet_corners(mesh: &Mesh, f: &Facet) -> (u32, u32) {
    let c = f.cell as usize;
    let p = mesh.degree[c] as usize;
    let ln = f.local_nodes(p);
    let nodes = mesh.cell_nodes(c);
    (nodes[ln[0]], nodes[ln[p]])
}

/// All sides of all cells, paired: `(facet, neighbour facet, same orientation)`.
pub(super) fn side_pairs(mesh: &Mesh) -> Vec<(Facet, Option<(Facet, bool)>)> {
    let sides: Vec<(Facet, (u32, u32))> = (0..mesh.n_cells() as u32)
        .flat_map(|cell| (0..4u8).map(move |side| Facet { cell, side }))
        .map(|f| (f, facet_corners(mesh, &f)))
        .collect();
    let mut by_edge: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    for (k, (_, (a, b))) in sides.iter().enumerate() {
        by_edge
            .entry(((*a).min(*b), (*a).max(*b)))
            .or_default()
            .push(k);
    }
    sides
        .iter()
        .map(|&(f, (a, b))| {
            let other = by_edge[&(a.min(b), a.max(b))]
                .iter()
                .map(|&k| sides[k])
                .find(|(g, _)| g.cell != f.cell)
                .map(|(g, (first, _))| (g, first == a));
            (f, other)
        })
        .collect()
}

/// P N (N the unit outward normal of the cell) at side parameter `s` of facet `f`, with the
/// face's length element |dX/ds| and the point X.
pub(super) fn traction(
    model: &SolidModel,
    dofs: &DofMap,
    x: &[f64],
    f: &Facet,
    s: f64,
) -> Option<(Vec2, f64, Vec2)> {
    let (st, n, len) = side_state(model, dofs, x, f, s)?;
    Some((st.p * n, len, st.x))
}

/// The point state at side parameter `s` of facet `f`, the cell's unit outward normal N there
/// and the length element |dX/ds|.
pub(super) fn side_state(
    model: &SolidModel,
    dofs: &DofMap,
    x: &[f64],
    f: &Facet,
    s: f64,
) -> Option<(PointState, Vec2, f64)> {
    let c = f.cell as usize;
    let (xi, eta) = f.ref_point(s);
    let st = point_state(model, dofs, x, c, xi, eta)?;
    let t = st.jac.column(f.tangent_column()).into_owned();
    let len = t.norm();
    let mut n = Vec2::new(t[1], -t[0]) / len;
    // Outward: along +∂X/∂ξ on side 1, −∂X/∂ξ on side 0 (η likewise on sides 3 and 2).
    let across = st.jac.column(1 - f.tangent_column()).into_owned();
    let sign = if f.side % 2 == 1 { 1.0 } else { -1.0 };
    if n.dot(&across) * sign < 0.0 {
        n = -n;
    }
    Some((st, n, len))
}

/// Tractions applied on boundary facets (e.g. by the road's contact), sampled at the points
/// `points` (side parameter s ∈ [−1, 1]) of each facet with weights `weights`:
/// `traction[f · points.len() + q]` is the force per reference length on the body at point q
/// of facet f.
#[derive(Clone, Debug, Default)]
pub struct BoundaryTractions {
    pub facets: Vec<Facet>,
    pub points: Vec<f64>,
    pub weights: Vec<f64>,
    pub traction: Vec<Vec2>,
}

/// The explicit residual estimator (see the module docs). `free` names the traction-free facet
/// sets of the mesh.
pub fn explicit_residual(
    model: &SolidModel,
    dofs: &DofMap,
    x: &[f64],
    free: &[&str],
) -> CellEstimate {
    explicit_residual_with(model, dofs, x, free, None)
}

/// [`explicit_residual`] with the tractions `applied` on boundary facets: the residual of
/// such a side is t − P N (a side both free and loaded counts as free).
pub fn explicit_residual_with(
    model: &SolidModel,
    dofs: &DofMap,
    x: &[f64],
    free: &[&str],
    applied: Option<&BoundaryTractions>,
) -> CellEstimate {
    let mesh = &model.mesh;
    let nc = mesh.n_cells();
    let mut free_sides: std::collections::HashSet<(u32, u8)> = Default::default();
    for name in free {
        for f in mesh.facet_set(name) {
            free_sides.insert((f.cell, f.side));
        }
    }
    let pairs = side_pairs(mesh);
    let mu: Vec<f64> = (0..nc)
        .map(|c| model.material_of(c).small_strain_shear_modulus())
        .collect();
    let diam: Vec<f64> = (0..nc)
        .map(|c| {
            let nodes = mesh.cell_nodes(c);
            let p = mesh.degree[c] as usize;
            let m = p + 1;
            let cn = [0, p, m * p, m * p + p].map(|a| mesh.nodes[nodes[a] as usize]);
            ((cn[0] - cn[3]).norm()).max((cn[1] - cn[2]).norm())
        })
        .collect();
    // Interior residual.
    let mut sq: Vec<f64> = (0..nc)
        .into_par_iter()
        .map(|c| {
            let p = mesh.degree[c] as f64;
            let (pts, wts) = gauss_1d(error_rule(mesh.degree[c] as usize));
            let mut sum = 0.0;
            for (l, &eta) in pts.iter().enumerate() {
                for (i, &xi) in pts.iter().enumerate() {
                    if let Some((r, w)) = interior_residual(model, dofs, x, c, xi, eta) {
                        sum += wts[i] * wts[l] * w * r.norm_squared();
                    }
                }
            }
            (diam[c] / p).powi(2) * sum / mu[c]
        })
        .collect();
    // Faces: each side of each cell adds its own share (½ of an interior jump, all of a free
    // face's traction), so a shared face is split evenly between its two cells.
    let face_sq: Vec<(usize, f64)> = pairs
        .par_iter()
        .filter_map(|(f, other)| {
            let c = f.cell as usize;
            let free_face = other.is_none() && free_sides.contains(&(f.cell, f.side));
            if other.is_none() && !free_face {
                return None;
            }
            let p = mesh.degree[c] as usize;
            let (pts, wts) = gauss_1d(p + 2);
            let mut sum = 0.0;
            let mut length = 0.0;
            for (&s, &w) in pts.iter().zip(&wts) {
                let (t, len, _) = traction(model, dofs, x, f, s)?;
                let jump = match other {
                    None => t,
                    Some((g, same)) => {
                        let s2 = if *same { s } else { -s };
                        let (t2, _, _) = traction(model, dofs, x, g, s2)?;
                        t + t2
                    }
                };
                let scale = if other.is_some() { 0.5 } else { 1.0 };
                sum += scale * w * len * jump.norm_squared();
                length += w * len;
            }
            Some((c, length / p as f64 * sum / mu[c]))
        })
        .collect();
    for (c, v) in face_sq {
        sq[c] += v;
    }
    if let Some(bt) = applied {
        let nq = bt.points.len();
        for (k, f) in bt.facets.iter().enumerate() {
            if free_sides.contains(&(f.cell, f.side)) || bt.traction.len() < (k + 1) * nq {
                continue;
            }
            let c = f.cell as usize;
            let mut sum = 0.0;
            let mut length = 0.0;
            for q in 0..nq {
                let Some((pn, len, _)) = traction(model, dofs, x, f, bt.points[q]) else {
                    continue;
                };
                let r = bt.traction[k * nq + q] - pn;
                sum += bt.weights[q] * len * r.norm_squared();
                length += bt.weights[q] * len;
            }
            sq[c] += length / f64::from(mesh.degree[c]) * sum / mu[c];
        }
    }
    CellEstimate::from_squares(sq)
}

/// Strong residual Div P + b − ρ ω² ∂θθχ at (ξ, η) of cell `c` and the weight det(dX/dξ).
fn interior_residual(
    model: &SolidModel,
    dofs: &DofMap,
    x: &[f64],
    c: usize,
    xi: f64,
    eta: f64,
) -> Option<(Vec2, f64)> {
    const D: f64 = 1e-4;
    let s0 = point_state(model, dofs, x, c, xi, eta)?;
    let inv = s0.jac.try_inverse()?;
    let rw2 = model.rho_of(c) * model.omega2;
    // P and g = ∂θχ = t + H t at the four neighbours (ξ ± D, η), (ξ, η ± D).
    let at = |a: f64, b: f64| -> Option<(Mat2, Vec2)> {
        let s = point_state(model, dofs, x, c, a, b)?;
        let t = Vec2::new(-s.x[1], s.x[0]);
        Some((s.p, t + s.h * t))
    };
    let (pxp, gxp) = at(xi + D, eta)?;
    let (pxm, gxm) = at(xi - D, eta)?;
    let (pep, gep) = at(xi, eta + D)?;
    let (pem, gem) = at(xi, eta - D)?;
    let dp = [(pxp - pxm) / (2.0 * D), (pep - pem) / (2.0 * D)];
    let dg = [(gxp - gxm) / (2.0 * D), (gep - gem) / (2.0 * D)];
    // ∂/∂X_J = Σ_k ∂/∂ξ_k (∂ξ_k/∂X_J).
    let mut div = Vec2::zeros();
    let mut grad_g = Mat2::zeros();
    for jj in 0..2 {
        for k in 0..2 {
            let w = inv[(k, jj)];
            div += dp[k].column(jj) * w;
            for i in 0..2 {
                grad_g[(i, jj)] += dg[k][i] * w;
            }
        }
    }
    let t = Vec2::new(-s0.x[1], s0.x[0]);
    let mut r = div - grad_g * t * rw2;
    if let Some(b) = model.body_force.as_ref() {
        r += b(s0.x);
    }
    Some((r, s0.jac.determinant().abs()))
}

/// The interpolation estimator with recovered derivatives (see the module docs).
pub fn interpolation(model: &SolidModel, dofs: &DofMap, x: &[f64]) -> CellEstimate {
    let nodal = recover_gradient(model, dofs, x);
    let mesh = &model.mesh;
    // g_d = ∂u/∂ξ_d = H* ∂X/∂ξ_d along reference direction d.
    let g = |c: usize, xi: f64, eta: f64, d: usize| -> Option<Vec2> {
        let jac = model.point_values_geometry(c, xi, eta)?;
        Some(recovered_at(mesh, &nodal, c, xi, eta) * jac.column(d))
    };
    let sq = (0..mesh.n_cells())
        .into_par_iter()
        .map(|c| {
            let p = mesh.degree[c] as usize;
            if p > 2 {
                return 0.0;
            }
            let cp = crate::adapt::estimate::interpolation_constant(p) * 4f64.powi(p as i32);
            let (pts, wts) = gauss_1d(error_rule(p));
            let mut sum = 0.0;
            for (l, &eta) in pts.iter().enumerate() {
                for (i, &xi) in pts.iter().enumerate() {
                    let Some(s) = point_state(model, dofs, x, c, xi, eta) else {
                        continue;
                    };
                    let Some(inv) = s.jac.try_inverse() else {
                        continue;
                    };
                    let w = wts[i] * wts[l] * s.jac.determinant().abs();
                    for d in 0..2 {
                        let at = |t: f64| {
                            if d == 0 {
                                g(c, xi + t, eta, d)
                            } else {
                                g(c, xi, eta + t, d)
                            }
                        };
                        // ∂^p of g_d by central differences.
                        let gd = if p == 1 {
                            const H: f64 = 1e-4;
                            match (at(H), at(-H)) {
                                (Some(a), Some(b)) => (a - b) / (2.0 * H),
                                _ => continue,
                            }
                        } else {
                            const H: f64 = 1e-3;
                            match (at(H), at(0.0), at(-H)) {
                                (Some(a), Some(m), Some(b)) => (a - 2.0 * m + b) / (H * H),
                                _ => continue,
                            }
                        };
                        // n_d = ∇ξ_d: row d of (dX/dξ)⁻¹.
                        let nd = Vec2::new(inv[(d, 0)], inv[(d, 1)]);
                        let e = gd * nd.transpose();
                        sum += cp * w * energy_density(model, c, &s, &e);
                    }
                }
            }
            sum
        })
        .collect();
    CellEstimate::from_squares(sq)
}
