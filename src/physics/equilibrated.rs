//! The implicit (equilibrated residual) error estimator of the finite-strain solid: local
//! Neumann problems on every cell with equilibrated boundary tractions (Ainsworth–Oden).
//!
//! # Equations
//!
//! The error is measured in the energy norm of the problem linearised about the converged
//! state, `‖e‖²_A = Σ_K ∫_K ∇e : A : ∇e` (see [`super::estimate`]). With the total stress of the
//! state `Σ_h = P_h − ρ ω² (∂θχ_h ⊗ t)` (`t = (−X₂, X₁)`; the second term is the θ-referential
//! inertia of the steady and spinning modes, in the weak form the element kernels use), the
//! residual of a cell K against tractions `g_K` on its sides is
//!
//! ```text
//! R_K(v) = ∫_K (b · v − Σ_h : ∇v) dX + ∮_{∂K} g_K · v dS.
//! ```
//!
//! 1. **Averaged tractions.** On an interior side `g = ½ (Σ_h N)⁻ − ½ (Σ_h N)⁺` (out of the
//!    side's first cell, the negative for the other); on a traction-free side `g = 0`; on a side
//!    with applied tractions (contact) `g = t`; on a side with a displacement condition (the hub)
//!    the one-sided `Σ_h N`, which the equilibration may change freely.
//! 2. **Equilibration.** For every vertex n with its bilinear hat θ_n and each direction e_i,
//!    linear corrections Δg on the sides at n (moments `μ_F^n = ∫_F Δg_i θ_n`) are chosen, of
//!    minimum norm, such that `R_K(θ_n e_i) = 0` in every cell K around n. The conditions are
//!    solvable because the global residual vanishes against θ_n e_i (the state is converged and
//!    the hats lie in the finite element space); the sides' linear corrections follow from
//!    their two end moments.
//! 3. **Local Neumann problems.** In every cell, `φ_K` in vector Q_{p+2} (Lagrange on
//!    Gauss–Lobatto points, p the cell's degree, at most 4) with `φ_K = 0` on sides with a
//!    displacement condition solves `∫_K ∇v : A : ∇φ_K = R_K(v)` for all such v; the
//!    components of R_K along the null space of the local form (translations, and rotations of
//!    an unstressed cell) are dropped (they vanish up to round-off after the equilibration, on
//!    cells with a bilinear map exactly). The indicator is `η_K² = ∫_K ∇φ_K : A : ∇φ_K`.
//!
//! For a linear problem with exact local solutions, `Σ_K η_K² ≥ ‖e‖²` (a guaranteed upper
//! bound); here the local space is finite (p + 2). Measured on a manufactured solution of the
//! static solid (`tests/mms.rs`): effectivity 1.09–1.20 (Q1) and 1.26–1.50 (Q2). With a spin,
//! the linearised operator of the θ-referential problem has the inertia part
//! `−ρ ω² ∫ (∇e t)·(∇v t)`, which the local problems (and the error measure) omit: while
//! `ρ ω² R²` is small next to the shear modulus the effectivity is that of the static solid;
//! when it is comparable (fast spinning: 5.9 μ at the rim in `tests/solid_estimators.rs`) the
//! estimator overestimates the material-norm error by a factor of 2–4, most in the cells at the
//! hub. The volume terms of the equilibration use the element kernels' Gauss rule, so the
//! moments of a converged state balance to round-off.
//!
//! **Hanging nodes** (one-irregular refinement): a small cell's side against half of a big
//! cell's side is a side of its own, the big cell's parameter an affine map of the small one's;
//! the hat of a hanging vertex is its big side's end hats at its position (the conforming
//! bilinear space, as the displacement constraints make it), so its moments go to those two
//! vertices. Scope: the elastic stress of the state (not the strain-rate damping or a viscous
//! overstress).

use super::estimate::{
    point_state, side_pairs, side_state, tangent, BoundaryTractions, PointState, SolidContext,
};
use super::solid::SolidModel;
use super::streamline_upwind::{lagrange_with_derivative, reference_of};
use crate::adapt::marking::{CellEstimate, CellEstimator};
use crate::assembly::DofMap;
use crate::element::quadrature::gauss_1d;
use crate::math::{Mat2, Vec2};
use crate::mesh::locate::{point_at, PointLocator};
use crate::mesh::{Facet, Mesh};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::collections::{HashMap, HashSet};

/// What lies across a side without a partner of the same corners.
enum Across {
    /// Nothing: a boundary side.
    Boundary,
    /// A big side covered by two small cells' sides.
    Covered,
    /// This is a small side on the big cell's facet `big`, whose parameter is `a s + b`.
    Half { big: Facet, a: f64, b: f64 },
}

/// Classify the unpartnered side `f` (see [`Across`]) by locating a point just outside it at
/// s = ½ and reading its two ends in the cell found there.
fn across(mesh: &Mesh, locator: &PointLocator, f: &Facet) -> Across {
    let c = f.cell as usize;
    let (xi, eta) = f.ref_point(0.5);
    let x = point_at(mesh, c, xi, eta);
    // Outward: from the cell's centre through the point, a small step.
    let centre = point_at(mesh, c, 0.0, 0.0);
    let step = (x - centre) * 1e-6;
    let Some((other, _, _)) = locator.locate(mesh, x + step).filter(|l| l.0 != c) else {
        return Across::Boundary;
    };
    let ends = [-1.0, 1.0].map(|s| {
        let (a, b) = f.ref_point(s);
        point_at(mesh, c, a, b)
    });
    let Some(r) = ends
        .iter()
        .map(|&p| reference_of(mesh, other, p))
        .collect::<Option<Vec<(f64, f64)>>>()
    else {
        return Across::Covered;
    };
    let tol = 1e-6;
    let on = |v: f64, w: f64| (v - w).abs() < tol;
    let inside = |v: f64| v.abs() <= 1.0 + tol;
    for side in 0..4u8 {
        // (coordinate fixed on the side, the side's parameter) of a reference point.
        let split = |p: &(f64, f64)| if side < 2 { (p.0, p.1) } else { (p.1, p.0) };
        let target = if side % 2 == 0 { -1.0 } else { 1.0 };
        if r.iter().all(|p| {
            let (fixed, free) = split(p);
            on(fixed, target) && inside(free)
        }) {
            let (s0, s1) = (split(&r[0]).1, split(&r[1]).1);
            return Across::Half {
                big: Facet {
                    cell: other as u32,
                    side,
                },
                a: 0.5 * (s1 - s0),
                b: 0.5 * (s0 + s1),
            };
        }
    }
    Across::Covered
}

/// A side before its hats and quadrature: first facet, the other with its parameter map, kind.
type RawSide = (Facet, Option<(Facet, f64, f64)>, Kind);

/// Moments per (side or vertex) index and component.
type PatchMoments = Vec<(usize, [f64; 2])>;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Interior,
    Free,
    Dirichlet,
    Loaded(usize),
}

/// One side of the mesh: its first cell's facet; the other cell's facet with the affine map of
/// the side parameter onto it (`s⁺ = a s + b`: a = ±1 between equal cells, ±½ from a small
/// cell onto the half of a big cell's side it covers); the vertices whose (conforming) hat does
/// not vanish on the side, with the hat's values at s = −1 and s = +1; per quadrature point
/// (s, w |dX/ds|, averaged traction out of the first cell).
struct Side {
    minus: Facet,
    plus: Option<(Facet, f64, f64)>,
    kind: Kind,
    theta: Vec<(usize, f64, f64)>,
    points: Vec<(f64, f64, Vec2)>,
}

impl Side {
    /// The hat of vertex `v` at parameter s (0 if it vanishes on the side).
    fn theta_at(&self, v: usize, s: f64) -> f64 {
        self.theta
            .iter()
            .find(|t| t.0 == v)
            .map_or(0.0, |&(_, t0, t1)| {
                0.5 * (1.0 - s) * t0 + 0.5 * (1.0 + s) * t1
            })
    }
}

/// Σ_h = P_h − ρ ω² (∂θχ_h ⊗ t) at a point state of cell `c`.
fn total_stress(model: &SolidModel, c: usize, s: &PointState) -> Mat2 {
    let rw2 = model.rho_of(c) * model.omega2;
    if rw2 == 0.0 {
        return s.p;
    }
    let t = Vec2::new(-s.x[1], s.x[0]);
    let dth = t + s.h * t;
    s.p - dth * t.transpose() * rw2
}

/// What the residual and the local problem use at a Gauss point of a cell: its reference
/// coordinates, state, inverse Jacobian, weight w det J, total stress and body force.
struct CellPoint {
    xi: f64,
    eta: f64,
    st: PointState,
    inv: Mat2,
    w: f64,
    sig: Mat2,
    bf: Vec2,
}

/// The points of the n × n Gauss rule of cell `c` (degenerate points left out).
fn cell_points(model: &SolidModel, dofs: &DofMap, x: &[f64], c: usize, n: usize) -> Vec<CellPoint> {
    let (pts, wts) = gauss_1d(n);
    let mut out = Vec::with_capacity(n * n);
    for (l, &eta) in pts.iter().enumerate() {
        for (i, &xi) in pts.iter().enumerate() {
            let Some(st) = point_state(model, dofs, x, c, xi, eta) else {
                continue;
            };
            let Some(inv) = st.jac.try_inverse() else {
                continue;
            };
            out.push(CellPoint {
                xi,
                eta,
                inv,
                w: wts[i] * wts[l] * st.jac.determinant().abs(),
                sig: total_stress(model, c, &st),
                bf: model.body_force.as_ref().map_or(Vec2::zeros(), |f| f(st.x)),
                st,
            });
        }
    }
    out
}

/// Σ_h N (N the cell's outward unit normal) at parameter `s` of facet `f`, with |dX/ds|.
fn side_traction(
    model: &SolidModel,
    dofs: &DofMap,
    x: &[f64],
    f: &Facet,
    s: f64,
) -> Option<(Vec2, f64)> {
    let (st, n, len) = side_state(model, dofs, x, f, s)?;
    Some((total_stress(model, f.cell as usize, &st) * n, len))
}

/// Corner nodes of cell `c` in the order of the bilinear hats (ξ, η) = (−,−), (+,−), (−,+), (+,+).
fn corners(mesh: &Mesh, c: usize) -> [u32; 4] {
    let p = usize::from(mesh.degree[c]);
    let m = p + 1;
    let nodes = mesh.cell_nodes(c);
    [0, p, m * p, m * p + p].map(|a| nodes[a])
}

/// Bilinear hats at (ξ, η) and their reference gradients.
fn hats(xi: f64, eta: f64) -> ([f64; 4], [[f64; 2]; 4]) {
    let (a, da) = ([0.5 * (1.0 - xi), 0.5 * (1.0 + xi)], [-0.5, 0.5]);
    let (b, db) = ([0.5 * (1.0 - eta), 0.5 * (1.0 + eta)], [-0.5, 0.5]);
    let mut n = [0.0; 4];
    let mut dn = [[0.0; 2]; 4];
    for k in 0..4 {
        let (i, j) = (k % 2, k / 2);
        n[k] = a[i] * b[j];
        dn[k] = [da[i] * b[j], a[i] * db[j]];
    }
    (n, dn)
}

/// Gauss–Lobatto points of degree q (q + 1 points), 1 ≤ q ≤ 4.
fn lobatto(q: usize) -> Vec<f64> {
    match q {
        1 => vec![-1.0, 1.0],
        2 => vec![-1.0, 0.0, 1.0],
        3 => {
            let a = 1.0 / 5f64.sqrt();
            vec![-1.0, -a, a, 1.0]
        }
        _ => {
            let a = (3.0f64 / 7.0).sqrt();
            vec![-1.0, -a, 0.0, a, 1.0]
        }
    }
}

/// The equilibrated residual estimator ([`equilibrated`]) behind the shared interface, with the
/// context's free sets and applied tractions.
pub struct Equilibrated;

impl CellEstimator<SolidContext<'_>> for Equilibrated {
    type Error = std::convert::Infallible;
    fn name(&self) -> &'static str {
        "equilibrated residual"
    }
    fn estimate(&self, ctx: &SolidContext) -> Result<CellEstimate, Self::Error> {
        Ok(equilibrated(
            ctx.model,
            ctx.dofs,
            ctx.x,
            ctx.free,
            ctx.applied,
        ))
    }
}

/// The equilibrated residual estimator (see the module docs). `free` names the traction-free
/// facet sets; `applied` gives tractions on boundary facets (e.g. the road's contact); every
/// other boundary side carries a displacement condition.
pub fn equilibrated(
    model: &SolidModel,
    dofs: &DofMap,
    x: &[f64],
    free: &[&str],
    applied: Option<&BoundaryTractions>,
) -> CellEstimate {
    let mesh = &model.mesh;
    let nc = mesh.n_cells();
    let mut free_sides: HashSet<(u32, u8)> = HashSet::new();
    for name in free {
        for f in mesh.facet_set(name) {
            free_sides.insert((f.cell, f.side));
        }
    }
    let loaded: HashMap<(u32, u8), usize> = applied
        .map(|bt| {
            bt.facets
                .iter()
                .enumerate()
                .map(|(k, f)| ((f.cell, f.side), k))
                .collect()
        })
        .unwrap_or_default();
    // Vertices: the corner nodes, numbered compactly.
    let mut vertex_of: HashMap<u32, usize> = HashMap::new();
    let cell_vertices: Vec<[usize; 4]> = (0..nc)
        .map(|c| {
            corners(mesh, c).map(|n| {
                let next = vertex_of.len();
                *vertex_of.entry(n).or_insert(next)
            })
        })
        .collect();
    let nv = vertex_of.len();
    let ends_of = |f: &Facet| -> [usize; 2] {
        let c = f.cell as usize;
        let p = usize::from(mesh.degree[c]);
        let ln = f.local_nodes(p);
        let nodes = mesh.cell_nodes(c);
        [ln[0], ln[p]].map(|a| vertex_of[&nodes[a]])
    };
    // Sides. A side without a partner of the same corners is a boundary side, a small cell's
    // side against half of a big cell's (one-irregular refinement), or that big side (covered
    // by the small ones, skipped): told apart by locating a point just outside it.
    let locator = PointLocator::new(mesh);
    // Hanging vertices: (vertex, [(master, weight)]).
    let mut hanging: HashMap<usize, Vec<(usize, f64)>> = HashMap::new();
    let mut raw: Vec<RawSide> = Vec::new();
    for (f, other) in side_pairs(mesh) {
        if let Some((g, same)) = other {
            if f.cell < g.cell {
                raw.push((
                    f,
                    Some((g, if same { 1.0 } else { -1.0 }, 0.0)),
                    Kind::Interior,
                ));
            }
            continue;
        }
        if free_sides.contains(&(f.cell, f.side)) {
            raw.push((f, None, Kind::Free));
            continue;
        }
        if let Some(&k) = loaded.get(&(f.cell, f.side)) {
            raw.push((f, None, Kind::Loaded(k)));
            continue;
        }
        match across(mesh, &locator, &f) {
            Across::Boundary => raw.push((f, None, Kind::Dirichlet)),
            Across::Covered => {}
            Across::Half { big, a, b } => {
                // The end inside the big side is a hanging vertex: its hat is the big side's
                // end hats at its parameter there.
                let ends = ends_of(&f);
                let big_ends = ends_of(&big);
                for (e, sb) in [(0, b - a), (1, b + a)] {
                    if sb.abs() < 1.0 - 1e-6 {
                        hanging.insert(
                            ends[e],
                            vec![
                                (big_ends[0], 0.5 * (1.0 - sb)),
                                (big_ends[1], 0.5 * (1.0 + sb)),
                            ],
                        );
                    }
                }
                raw.push((f, Some((big, a, b)), Kind::Interior));
            }
        }
    }
    let expand = |v: usize| -> Vec<(usize, f64)> {
        hanging.get(&v).cloned().unwrap_or_else(|| vec![(v, 1.0)])
    };
    let mut sides: Vec<Side> = raw
        .into_iter()
        .map(|(f, plus, kind)| {
            let ends = ends_of(&f);
            let mut theta: Vec<(usize, f64, f64)> = Vec::new();
            for (e, &v) in ends.iter().enumerate() {
                for (n, w) in expand(v) {
                    let ent = match theta.iter().position(|t| t.0 == n) {
                        Some(i) => &mut theta[i],
                        None => {
                            theta.push((n, 0.0, 0.0));
                            let last = theta.len() - 1;
                            &mut theta[last]
                        }
                    };
                    if e == 0 {
                        ent.1 += w;
                    } else {
                        ent.2 += w;
                    }
                }
            }
            Side {
                minus: f,
                plus,
                kind,
                theta,
                points: Vec::new(),
            }
        })
        .collect();
    sides.par_iter_mut().for_each(|sd| {
        let c = sd.minus.cell as usize;
        let p = usize::from(mesh.degree[c]);
        let rule: Vec<(f64, f64)> = match (sd.kind, applied) {
            (Kind::Loaded(_), Some(bt)) => bt
                .points
                .iter()
                .copied()
                .zip(bt.weights.iter().copied())
                .collect(),
            _ => {
                let (s, w) = gauss_1d(p + 3);
                s.into_iter().zip(w).collect()
            }
        };
        for (q, (s, w)) in rule.into_iter().enumerate() {
            let Some((tm, len)) = side_traction(model, dofs, x, &sd.minus, s) else {
                continue;
            };
            let g = match sd.kind {
                Kind::Interior => {
                    let Some((fp, a, b)) = sd.plus else { continue };
                    match side_traction(model, dofs, x, &fp, a * s + b) {
                        Some((tp, _)) => (tm - tp) * 0.5,
                        None => tm,
                    }
                }
                Kind::Free => Vec2::zeros(),
                Kind::Dirichlet => tm,
                Kind::Loaded(k) => applied.map_or(Vec2::zeros(), |bt| {
                    bt.traction
                        .get(k * bt.points.len() + q)
                        .copied()
                        .unwrap_or_default()
                }),
            };
            sd.points.push((s, w * len, g));
        }
    });
    let sides_of_cell = {
        let mut v: Vec<Vec<(usize, f64)>> = vec![Vec::new(); nc];
        for (k, sd) in sides.iter().enumerate() {
            v[sd.minus.cell as usize].push((k, 1.0));
            if let Some((fp, _, _)) = sd.plus {
                v[fp.cell as usize].push((k, -1.0));
            }
        }
        v
    };
    // Moments b_K^n = R_K(θ_n e_i) with the averaged tractions, per cell and (conforming)
    // vertex: the local hats' moments, a hanging corner's given to its masters.
    let local: Vec<[[f64; 2]; 4]> = (0..nc)
        .into_par_iter()
        .map(|c| {
            let mut b = [[0.0; 2]; 4];
            // The kernels' rule: the moments of a converged state then sum to zero around
            // every free vertex.
            for cp in cell_points(model, dofs, x, c, usize::from(mesh.degree[c]) + 1) {
                let (n, dn) = hats(cp.xi, cp.eta);
                for a in 0..4 {
                    let g = cp.inv.transpose() * Vec2::new(dn[a][0], dn[a][1]);
                    let r = cp.bf * n[a] - cp.sig * g;
                    b[a][0] += cp.w * r[0];
                    b[a][1] += cp.w * r[1];
                }
            }
            b
        })
        .collect();
    let mut moments: Vec<Vec<(usize, [f64; 2])>> = vec![Vec::new(); nc];
    let add = |list: &mut Vec<(usize, [f64; 2])>, n: usize, v: [f64; 2]| match list
        .iter_mut()
        .find(|e| e.0 == n)
    {
        Some(e) => {
            e.1[0] += v[0];
            e.1[1] += v[1];
        }
        None => list.push((n, v)),
    };
    for c in 0..nc {
        for a in 0..4 {
            for (n, w) in expand(cell_vertices[c][a]) {
                add(&mut moments[c], n, [w * local[c][a][0], w * local[c][a][1]]);
            }
        }
    }
    for sd in &sides {
        for &(s, wl, g) in &sd.points {
            for (cell, sgn) in std::iter::once((sd.minus.cell as usize, 1.0))
                .chain(sd.plus.map(|(fp, _, _)| (fp.cell as usize, -1.0)))
            {
                for &(n, _, _) in &sd.theta {
                    let th = sd.theta_at(n, s);
                    add(
                        &mut moments[cell],
                        n,
                        [sgn * wl * g[0] * th, sgn * wl * g[1] * th],
                    );
                }
            }
        }
    }
    // Patch problems per vertex: moments μ of least (weighted) norm with A μ = −b.
    let mut node_cells: Vec<Vec<(usize, [f64; 2])>> = vec![Vec::new(); nv];
    for (c, list) in moments.iter().enumerate() {
        for &(n, b) in list {
            node_cells[n].push((c, b));
        }
    }
    let mut node_sides: Vec<Vec<usize>> = vec![Vec::new(); nv];
    for (k, sd) in sides.iter().enumerate() {
        if matches!(sd.kind, Kind::Interior | Kind::Dirichlet) {
            for &(n, _, _) in &sd.theta {
                node_sides[n].push(k);
            }
        }
    }
    let patches: Vec<(usize, PatchMoments)> = (0..nv)
        .into_par_iter()
        .filter_map(|v| {
            let cells = &node_cells[v];
            let sl = &node_sides[v];
            if cells.is_empty() || sl.is_empty() {
                return None;
            }
            // Least weighted norm: a side with a displacement condition takes its correction
            // freely (its traction does not enter its cell's local problem), the others as
            // little as the balance needs.
            let d: Vec<f64> = sl
                .iter()
                .map(|&k| {
                    if sides[k].kind == Kind::Dirichlet {
                        1e3
                    } else {
                        1.0
                    }
                })
                .collect();
            let mut ad = DMatrix::<f64>::zeros(cells.len(), sl.len());
            let mut b = DMatrix::<f64>::zeros(cells.len(), 2);
            for (ci, &(c, bc)) in cells.iter().enumerate() {
                b[(ci, 0)] = -bc[0];
                b[(ci, 1)] = -bc[1];
                for (j, &k) in sl.iter().enumerate() {
                    if sides[k].minus.cell as usize == c {
                        ad[(ci, j)] += d[j];
                    }
                    if sides[k]
                        .plus
                        .is_some_and(|(fp, _, _)| fp.cell as usize == c)
                    {
                        ad[(ci, j)] -= d[j];
                    }
                }
            }
            let lam = (&ad * ad.transpose()).pseudo_inverse(1e-12).ok()? * b;
            let y = ad.transpose() * lam;
            Some((
                v,
                sl.iter()
                    .enumerate()
                    .map(|(j, &k)| (k, [d[j] * y[(j, 0)], d[j] * y[(j, 1)]]))
                    .collect(),
            ))
        })
        .collect();
    // μ per side: (vertex, moment per component).
    let mut mu: Vec<PatchMoments> = vec![Vec::new(); sides.len()];
    for (v, list) in patches {
        for (k, m) in list {
            mu[k].push((v, m));
        }
    }
    // Linear corrections per side: Δg = α₀ ψ₀ + α₁ ψ₁ (ψ the side's end hats), the moments
    // ∫ Δg θ_n = μ_n matched (in least squares when a hanging end gives three vertices).
    let corr: Vec<[Vec2; 2]> = sides
        .iter()
        .zip(&mu)
        .map(|(sd, m)| {
            if !matches!(sd.kind, Kind::Interior | Kind::Dirichlet) || sd.theta.is_empty() {
                return [Vec2::zeros(); 2];
            }
            let nt = sd.theta.len();
            let mut g = DMatrix::<f64>::zeros(nt, 2);
            for &(s, wl, _) in &sd.points {
                let psi = [0.5 * (1.0 - s), 0.5 * (1.0 + s)];
                for (i, &(n, _, _)) in sd.theta.iter().enumerate() {
                    let th = sd.theta_at(n, s);
                    g[(i, 0)] += wl * th * psi[0];
                    g[(i, 1)] += wl * th * psi[1];
                }
            }
            let Ok(gi) = g.pseudo_inverse(1e-14) else {
                return [Vec2::zeros(); 2];
            };
            let al = [0, 1].map(|comp| {
                let rhs = DVector::from_iterator(
                    nt,
                    sd.theta
                        .iter()
                        .map(|t| m.iter().find(|e| e.0 == t.0).map_or(0.0, |e| e.1[comp])),
                );
                &gi * rhs
            });
            [Vec2::new(al[0][0], al[1][0]), Vec2::new(al[0][1], al[1][1])]
        })
        .collect();
    // Local Neumann problems.
    let sq: Vec<f64> = (0..nc)
        .into_par_iter()
        .map(|c| local_problem(model, dofs, x, c, &sides, &sides_of_cell[c], &corr))
        .collect();
    CellEstimate::from_squares(sq)
}

/// η_K² of cell `c` from its local Neumann problem in vector Q_{p+2}.
fn local_problem(
    model: &SolidModel,
    dofs: &DofMap,
    x: &[f64],
    c: usize,
    sides: &[Side],
    mine: &[(usize, f64)],
    corr: &[[Vec2; 2]],
) -> f64 {
    let mesh = &model.mesh;
    let p = usize::from(mesh.degree[c]);
    let q = (p + 2).min(4);
    let nodes1 = lobatto(q);
    let m = q + 1;
    let nb = m * m;
    let n = 2 * nb;
    let mut kmat = DMatrix::<f64>::zeros(n, n);
    let mut rhs = DVector::<f64>::zeros(n);
    let mut lx = [0.0; 5];
    let mut dlx = [0.0; 5];
    let mut ly = [0.0; 5];
    let mut dly = [0.0; 5];
    let mut grads = vec![Vec2::zeros(); nb];
    let mut vals = vec![0.0; nb];
    for cp in cell_points(model, dofs, x, c, q + 2) {
        let a = tangent(model, c, &cp.st);
        let CellPoint {
            xi,
            eta,
            inv,
            w,
            sig,
            bf,
            ..
        } = cp;
        lagrange_with_derivative(&nodes1, xi, &mut lx[..m], &mut dlx[..m]);
        lagrange_with_derivative(&nodes1, eta, &mut ly[..m], &mut dly[..m]);
        for k in 0..nb {
            let (kx, ky) = (k % m, k / m);
            vals[k] = lx[kx] * ly[ky];
            grads[k] = inv.transpose() * Vec2::new(dlx[kx] * ly[ky], lx[kx] * dly[ky]);
        }
        for ka in 0..nb {
            let ga = grads[ka];
            for i in 0..2 {
                let r = bf[i] * vals[ka] - (sig[(i, 0)] * ga[0] + sig[(i, 1)] * ga[1]);
                rhs[2 * ka + i] += w * r;
                for kb in 0..nb {
                    let gb = grads[kb];
                    for j in 0..2 {
                        let mut v = 0.0;
                        for jj in 0..2 {
                            for ll in 0..2 {
                                v += ga[jj] * a[(2 * i + jj, 2 * j + ll)] * gb[ll];
                            }
                        }
                        kmat[(2 * ka + i, 2 * kb + j)] += w * v;
                    }
                }
            }
        }
    }
    // Side tractions; DOFs on sides with a displacement condition are removed.
    let mut fixed = vec![false; n];
    for &(k, sgn) in mine {
        let sd = &sides[k];
        let (facet, map) = if sgn > 0.0 {
            (sd.minus, (1.0, 0.0))
        } else {
            match sd.plus {
                Some((fp, a, b)) => (fp, (a, b)),
                None => continue,
            }
        };
        if sd.kind == Kind::Dirichlet {
            for kk in 0..nb {
                let (kx, ky) = (kk % m, kk / m);
                let on = match facet.side {
                    0 => kx == 0,
                    1 => kx == q,
                    2 => ky == 0,
                    _ => ky == q,
                };
                if on {
                    fixed[2 * kk] = true;
                    fixed[2 * kk + 1] = true;
                }
            }
            continue;
        }
        for &(s, wl, g) in &sd.points {
            let th = [0.5 * (1.0 - s), 0.5 * (1.0 + s)];
            let flux = (g + corr[k][0] * th[0] + corr[k][1] * th[1]) * sgn;
            let (xi, eta) = facet.ref_point(map.0 * s + map.1);
            lagrange_with_derivative(&nodes1, xi, &mut lx[..m], &mut dlx[..m]);
            lagrange_with_derivative(&nodes1, eta, &mut ly[..m], &mut dly[..m]);
            for kk in 0..nb {
                let v = lx[kk % m] * ly[kk / m];
                rhs[2 * kk] += wl * flux[0] * v;
                rhs[2 * kk + 1] += wl * flux[1] * v;
            }
        }
    }
    let keep: Vec<usize> = (0..n).filter(|&i| !fixed[i]).collect();
    let mut kr = DMatrix::from_fn(keep.len(), keep.len(), |i, j| kmat[(keep[i], keep[j])]);
    let mut rr = DVector::from_fn(keep.len(), |i, _| rhs[keep[i]]);
    if keep.len() == n {
        // A floating cell: its data is balanced against translations by the equilibration,
        // and against the rotation only up to the cell's curvature (the hats span the
        // rotation on a bilinear map). The local problem is solved orthogonally to the rigid
        // modes, so a stressed cell's weak rotational stiffness does not turn that imbalance
        // into a spurious rotation.
        let mut rm = DMatrix::<f64>::zeros(n, 3);
        for kk in 0..nb {
            let xk = point_at(mesh, c, nodes1[kk % m], nodes1[kk / m]);
            rm[(2 * kk, 0)] = 1.0;
            rm[(2 * kk + 1, 1)] = 1.0;
            rm[(2 * kk, 2)] = -xk[1];
            rm[(2 * kk + 1, 2)] = xk[0];
        }
        let q = rm.qr().q();
        let proj = DMatrix::<f64>::identity(n, n) - &q * q.transpose();
        kr = &proj * kr * &proj;
        rr = &proj * rr;
        // The rigid modes, now a null space of kr and orthogonal to rr, get a unit-scale
        // stiffness: the Cholesky solve then returns the solution orthogonal to them.
        let scale = (0..n).map(|i| kr[(i, i)]).sum::<f64>() / n as f64;
        let mut spd = kr.clone();
        spd += &q * q.transpose() * scale;
        if let Some(ch) = spd.cholesky() {
            return rr.dot(&ch.solve(&rr));
        }
    } else if let Some(ch) = kr.clone().cholesky() {
        return rr.dot(&ch.solve(&rr));
    }
    // Not positive definite: in a compressed cell the initial-stress part of the tangent makes
    // rotation-like local modes slightly negative (a third of the cells along an adaptive
    // indentation), and a tangent may lose ellipticity. The local problem keeps its positive
    // part (an eigen-decomposition, several times the cost of the Cholesky solve).
    let eig = nalgebra::SymmetricEigen::new(kr);
    let lmax = eig.eigenvalues.iter().fold(0.0f64, |a, &v| a.max(v.abs()));
    let mut e2 = 0.0;
    for (j, &lam) in eig.eigenvalues.iter().enumerate() {
        if lam > 1e-10 * lmax {
            let proj = eig.eigenvectors.column(j).dot(&rr);
            e2 += proj * proj / lam;
        }
    }
    e2
}
