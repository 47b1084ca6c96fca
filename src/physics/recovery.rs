//! Recovered (smoothed, superconvergent) nodal Cauchy stress on any quadrilateral mesh:
//! Zienkiewicz–Zhu superconvergent patch recovery (SPR).
//!
//! **Samples.** In every cell the Cauchy stress σ = P Fᵀ / J (P of the cell's law, minus the
//! element pressure of a mixed formulation, exactly as [`SolidModel::point_values`]) and the
//! plane-strain out-of-plane stress σ33 (the law's, F33 = 1, minus the pressure) are evaluated at
//! the superconvergent points of the element: the p × p Gauss points of a degree-p cell (the
//! centre of a Q1 cell, the 2 × 2 Gauss points ξ, η = ±1/√3 of a Q2 cell), where the gradient of
//! the finite element solution is one order more accurate than elsewhere. Each sample is the
//! vector s = (σ11, σ22, σ12, σ33) at the sample's reference position X.
//!
//! **Patch fit.** For every vertex z of the mesh (a corner node of a cell) the patch is the set
//! of cells that have z as a corner. A polynomial per component,
//! s*(X) = Σ_k a_k φ_k(d), d = (X − z)/h, h the largest distance of a patch sample from z,
//! is fitted to the n samples X_i of the patch by least squares,
//!
//! ```text
//! min_a Σ_i |Σ_k a_k φ_k(d_i) − s(X_i)|²   ⇔   (Σ_i φ(d_i) φ(d_i)ᵀ) a = Σ_i φ(d_i) s(X_i)ᵀ,
//! ```
//!
//! with a complete polynomial: φ = (1, d1, d2) (P1) for a patch of Q1 cells (one sample per
//! cell, four in an interior patch) and the complete cubic φ = (1, d1, d2, d1², d1 d2, d2²,
//! d1² d2, d1 d2², d1³, d2³) (P3) for a patch with a Q2 cell (sixteen samples in an interior
//! patch). The cubic is one degree above the element's: the samples are accurate to O(h³) and a
//! quadratic fit would add an O(h³) truncation error of its own, which dominates at the boundary
//! nodes where the patch polynomial is extrapolated. Complete polynomials are invariant under
//! rotations of the mesh. The normal equations are 10 × 10 (fixed-size, no allocation, solved
//! by a Cholesky factorization; a symmetric eigendecomposition decides the rare patch whose rank
//! the factorization leaves open); a patch whose samples cannot determine the polynomial
//! (too few samples, samples on too few lines: smallest singular value below 1e-12 of the
//! largest diagonal entry) is fitted with the next lower complete degree (P2, P1, P0).
//!
//! **Nodal values.** Only patches of *interior* vertices (vertices on no boundary facet; a
//! boundary facet is a cell side that no other cell shares) are used, as Zienkiewicz and Zhu do:
//! every node of the mesh (vertices, side and centre nodes of Q2 cells, boundary nodes) takes
//! the average of the polynomials of all interior patches that contain it, evaluated at the
//! node. A boundary node thus gets values extrapolated from the interior patches next to it,
//! which are more accurate than a fit on the one-sided boundary patch. Nodes that no interior
//! patch contains (e.g. a mesh one cell thick) use the patch of a boundary vertex of their
//! cells, enlarged by the cells that share a vertex with it; a node that no fit reaches at all
//! (only cells with no finite sample) keeps the mean of the finite samples of its cells, or 0.
//! Every value is finite.
//!
//! **Exactness.** If the sampled stress is a polynomial of the fitted degree in X on a patch,
//! the fit reproduces it exactly; in particular a homogeneous deformation (constant stress, which Q1 and
//! Q2 represent exactly) is recovered to round-off at every node. For a smooth solution the
//! recovered stress at the nodes converges one order faster (or more) than the stress of the
//! elements evaluated at the nodes (spinning annulus, Q2: σ_r on the hub converges like h³
//! against h² for the element stresses; `tests/recovery.rs`).
//!
//! Conventions: components in the global Cartesian basis (x1, x2) of the reference
//! configuration, as functions of the reference position X (the mesh nodes); plane strain, per
//! unit thickness; units of stress of the scene (F/L²).

use super::solid::{PressureMode, SolidModel};
use crate::assembly::DofMap;
use crate::material::Hyperelastic as _;
use crate::math::{Mat2, Vec2};
use crate::mesh::Mesh;
use nalgebra::{SMatrix, SVector};
use rayon::prelude::*;

/// Recovered nodal stress components `[σ11, σ22, σ12, σ33]`.
pub type Stress4 = [f64; 4];

/// Number of monomials of the patch fits ([`monomials`]; a fit uses a subset, [`masks`]).
const MAX_TERMS: usize = 10;
type Normal = SMatrix<f64, MAX_TERMS, MAX_TERMS>;
type Rhs = SMatrix<f64, MAX_TERMS, 4>;

/// The stress samples of one cell (at most 4: the 2 × 2 Gauss points of a Q2 cell).
#[derive(Clone, Copy, Debug, Default)]
pub struct CellSamples {
    /// Number of valid entries.
    pub n: usize,
    /// Reference positions of the sampling points.
    pub x: [Vec2; 4],
    /// Stress `[σ11, σ22, σ12, σ33]` at the sampling points.
    pub s: [Stress4; 4],
}

impl CellSamples {
    fn iter(&self) -> impl Iterator<Item = (&Vec2, &Stress4)> {
        self.x[..self.n].iter().zip(&self.s[..self.n])
    }
}

/// The superconvergent sampling points (ξ, η) of a degree-`p` cell: the centre (p = 1) or the
/// 2 × 2 Gauss points (p = 2).
pub fn sampling_points(p: usize) -> &'static [(f64, f64)] {
    const G: f64 = 0.577_350_269_189_625_8; // 1/√3
    const Q1: [(f64, f64); 1] = [(0.0, 0.0)];
    const Q2: [(f64, f64); 4] = [(-G, -G), (G, -G), (-G, G), (G, G)];
    if p <= 1 {
        &Q1
    } else {
        &Q2
    }
}

/// Cauchy stress `[σ11, σ22, σ12, σ33]` and reference position at point (ξ, η) of cell `c` of
/// the state `x` (full vector); `None` if the point is degenerate or the stress not finite.
pub fn cauchy_at(
    model: &SolidModel,
    dofs: &DofMap,
    x: &[f64],
    c: usize,
    xi: f64,
    eta: f64,
) -> Option<(Vec2, Stress4)> {
    let pv = model.point_values(c, dofs, x, xi, eta)?;
    let law = model.material_of(c);
    let s = pv.sigma;
    // σ = σ_law − p I for a mixed formulation: p = tr(σ_law − σ)/2.
    let pres = if matches!(model.pressure, PressureMode::None) {
        0.0
    } else {
        let f = Mat2::identity() + pv.grad_u;
        let sl = law.stress(&pv.grad_u) * f.transpose() / f.determinant();
        0.5 * (sl - s).trace()
    };
    let v = [
        s[(0, 0)],
        s[(1, 1)],
        0.5 * (s[(0, 1)] + s[(1, 0)]),
        law.cauchy_33(&pv.grad_u) - pres,
    ];
    v.iter().all(|a| a.is_finite()).then_some((pv.x, v))
}

/// Stress samples of every cell of the state `x` at the cells' superconvergent points.
pub fn cauchy_samples(model: &SolidModel, dofs: &DofMap, x: &[f64]) -> Vec<CellSamples> {
    (0..model.mesh.n_cells())
        .into_par_iter()
        .map(|c| {
            let mut cs = CellSamples::default();
            for &(xi, eta) in sampling_points(model.mesh.degree[c] as usize) {
                if let Some((p, s)) = cauchy_at(model, dofs, x, c, xi, eta) {
                    cs.x[cs.n] = p;
                    cs.s[cs.n] = s;
                    cs.n += 1;
                }
            }
            cs
        })
        .collect()
}

/// Recovered nodal Cauchy stress `[σ11, σ22, σ12, σ33]` of the state `x` (see the module docs).
pub fn recover_cauchy(model: &SolidModel, dofs: &DofMap, x: &[f64]) -> Vec<Stress4> {
    recover_nodal(&model.mesh, &cauchy_samples(model, dofs, x))
}

/// Local corner indices (tensor order) of a degree-`p` cell.
#[inline]
fn corners(p: usize) -> [usize; 4] {
    let m = p + 1;
    [0, p, m * p, m * p + p]
}

/// A fitted patch polynomial.
#[derive(Clone, Copy, Debug)]
struct Poly {
    z: Vec2,
    h: f64,
    coef: Rhs,
}

impl Poly {
    fn eval(&self, x: &Vec2) -> Stress4 {
        let phi = monomials(&((x - self.z) / self.h));
        let v = self.coef.transpose() * phi;
        [v[0], v[1], v[2], v[3]]
    }
}

#[inline]
fn monomials(d: &Vec2) -> SVector<f64, MAX_TERMS> {
    let (x, y) = (d[0], d[1]);
    SVector::<f64, MAX_TERMS>::from([
        1.0,
        x,
        y,
        x * x,
        x * y,
        y * y,
        x * x * y,
        x * y * y,
        x * x * x,
        y * y * y,
    ])
}

/// Bit masks (over [`monomials`]) of the fits tried, best first, for a patch of degree `p`:
/// P1 then P0 for Q1; P3, P2, P1, P0 for Q2.
fn masks(p: usize) -> &'static [u16] {
    const P0: u16 = 0b1;
    const P1: u16 = 0b111;
    const P2: u16 = 0b11_1111;
    const P3: u16 = 0b11_1111_1111;
    if p <= 1 {
        &[P1, P0]
    } else {
        &[P3, P2, P1, P0]
    }
}

/// Least-squares fit of the samples of `cells` around `z` with the complete polynomial of the
/// patch of degree `p` ([`masks`]), lowering the degree until the fit is determined; `None`
/// without samples.
fn fit(samples: &[CellSamples], cells: &[u32], z: Vec2, p: usize) -> Option<Poly> {
    let h = cells
        .iter()
        .flat_map(|&c| samples[c as usize].iter())
        .map(|(x, _)| (x - z).norm())
        .fold(0.0, f64::max);
    if !(h > 0.0 && h.is_finite()) {
        return None;
    }
    let mut a = Normal::zeros();
    let mut b = Rhs::zeros();
    let mut n = 0usize;
    for &c in cells {
        for (x, s) in samples[c as usize].iter() {
            let phi = monomials(&((x - z) / h));
            a += phi * phi.transpose();
            b += phi * SMatrix::<f64, 1, 4>::from_row_slice(s);
            n += 1;
        }
    }
    if n == 0 {
        return None;
    }
    for &mask in masks(p) {
        let on = |i: usize| mask & (1 << i) != 0;
        let k = mask.count_ones() as usize;
        if n < k {
            continue;
        }
        // The inactive terms get the identity rows: the active block is solved on its own.
        let mut ak = a;
        let mut bk = b;
        for i in (0..MAX_TERMS).filter(|&i| !on(i)) {
            for j in 0..MAX_TERMS {
                ak[(i, j)] = 0.0;
                ak[(j, i)] = 0.0;
            }
            ak[(i, i)] = 1.0;
            for j in 0..4 {
                bk[(i, j)] = 0.0;
            }
        }
        // The padding adds unit singular values; the samples' scaled monomials are at most 1,
        // so the active block's largest entry is at most n: relative rank test against it.
        let amax = (0..MAX_TERMS)
            .filter(|&i| on(i))
            .map(|i| a[(i, i)])
            .fold(0.0, f64::max);
        if let Some(coef) = fit_solve(ak, &bk, 1e-12 * amax) {
            if coef.iter().all(|v| v.is_finite()) {
                return Some(Poly { z, h, coef });
            }
        }
    }
    None
}

/// Solve the symmetric positive semi-definite normal equations `a c = b`; `None` when they are
/// singular: smallest eigenvalue (= singular value) of `a` at most `threshold`, the polynomial
/// not determined by the samples. Most patches are decided by a Cholesky factorization alone:
/// for symmetric positive definite `a` of order m the smallest eigenvalue λ lies in
/// [1/tr(a⁻¹), m/tr(a⁻¹)], so `a` is regular when 1/tr(a⁻¹) exceeds the threshold and singular
/// when m/tr(a⁻¹) does not. A matrix in between,
/// or one the factorization refuses, is decided and solved by its symmetric eigendecomposition.
/// (Not by nalgebra's singular value decomposition: on some well-conditioned 10 × 10 normal
/// matrices its factors do not reproduce the matrix, U Σ Vᵀ off by 5e-3 at a condition number
/// of 2e3, and the fit with them is wrong by as much.)
fn fit_solve(a: Normal, b: &Rhs, threshold: f64) -> Option<Rhs> {
    if let Some(chol) = a.cholesky() {
        // tr(a⁻¹) = ‖L⁻¹‖_F² (a = L Lᵀ): one triangular solve instead of the inverse.
        let trace_inv = chol
            .l_dirty()
            .solve_lower_triangular(&Normal::identity())
            .map_or(f64::NAN, |li| li.norm_squared());
        if trace_inv.is_finite() && trace_inv > 0.0 {
            if 1.0 / trace_inv > threshold {
                return Some(chol.solve(b));
            }
            if MAX_TERMS as f64 / trace_inv <= threshold {
                return None;
            }
        }
    }
    let eig = a.symmetric_eigen();
    if eig.eigenvalues.min().partial_cmp(&threshold) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let q = &eig.eigenvectors;
    let mut qtb = q.transpose() * b;
    for (i, &l) in eig.eigenvalues.iter().enumerate() {
        qtb.row_mut(i).scale_mut(1.0 / l);
    }
    Some(q * qtb)
}

/// Nodal values of SPR from the stress samples of every cell (`samples[c]`, at reference
/// positions) on `mesh`; see the module docs. Q1 and Q2 cells, any mix.
pub fn recover_nodal(mesh: &Mesh, samples: &[CellSamples]) -> Vec<Stress4> {
    let nn = mesh.n_nodes();
    let nc = mesh.n_cells();
    // Vertex → cells (CSR over the corner nodes).
    let mut count = vec![0usize; nn + 1];
    for c in 0..nc {
        let nodes = mesh.cell_nodes(c);
        for a in corners(mesh.degree[c] as usize) {
            count[nodes[a] as usize + 1] += 1;
        }
    }
    for i in 0..nn {
        count[i + 1] += count[i];
    }
    let off = count;
    let mut fill = off.clone();
    let mut v2c = vec![0u32; off[nn]];
    for c in 0..nc {
        let nodes = mesh.cell_nodes(c);
        for a in corners(mesh.degree[c] as usize) {
            let v = nodes[a] as usize;
            v2c[fill[v]] = c as u32;
            fill[v] += 1;
        }
    }
    let patch = |v: usize| &v2c[off[v]..off[v + 1]];
    // Boundary vertices: ends of sides (corner pairs) that belong to one cell only.
    let mut sides: std::collections::HashMap<(u32, u32), u32> = std::collections::HashMap::new();
    for c in 0..nc {
        let nodes = mesh.cell_nodes(c);
        let k = corners(mesh.degree[c] as usize).map(|a| nodes[a]);
        for (a, b) in [(k[0], k[1]), (k[1], k[3]), (k[3], k[2]), (k[2], k[0])] {
            *sides.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    let mut boundary = vec![false; nn];
    for (&(a, b), &m) in &sides {
        if m == 1 {
            boundary[a as usize] = true;
            boundary[b as usize] = true;
        }
    }
    let is_vertex: Vec<bool> = (0..nn).map(|v| off[v + 1] > off[v]).collect();
    let deg_of = |cells: &[u32]| {
        cells
            .iter()
            .map(|&c| mesh.degree[c as usize] as usize)
            .min()
            .unwrap_or(1)
    };
    // Interior patches.
    let polys: Vec<Option<Poly>> = (0..nn)
        .into_par_iter()
        .map(|v| {
            if !is_vertex[v] || boundary[v] {
                return None;
            }
            let cells = patch(v);
            fit(samples, cells, mesh.nodes[v], deg_of(cells))
        })
        .collect();
    let mut acc = vec![[0.0f64; 4]; nn];
    let mut cnt = vec![0u32; nn];
    // Last patch that wrote a node (a node shared by two cells of a patch counts once).
    let mut mark = vec![usize::MAX; nn];
    let mut add = |v: usize,
                   poly: &Poly,
                   cells: &[u32],
                   only: Option<&[u32]>,
                   acc: &mut [Stress4],
                   cnt: &mut [u32]| {
        for &c in cells {
            for &n in mesh.cell_nodes(c as usize) {
                let n = n as usize;
                if mark[n] == v || only.is_some_and(|o| o[n] != 0) {
                    continue;
                }
                mark[n] = v;
                let s = poly.eval(&mesh.nodes[n]);
                for (a, b) in acc[n].iter_mut().zip(s) {
                    *a += b;
                }
                cnt[n] += 1;
            }
        }
    };
    for (v, p) in polys.iter().enumerate() {
        if let Some(p) = p {
            add(v, p, patch(v), None, &mut acc, &mut cnt);
        }
    }
    // Nodes no interior patch reaches: enlarged patches of the boundary vertices of their cells.
    if cnt.contains(&0) {
        let covered = cnt.clone();
        let mut grown: Vec<u32> = Vec::new();
        for v in 0..nn {
            if !is_vertex[v] || !boundary[v] {
                continue;
            }
            let cells = patch(v);
            let needed = cells.iter().any(|&c| {
                mesh.cell_nodes(c as usize)
                    .iter()
                    .any(|&n| covered[n as usize] == 0)
            });
            if !needed {
                continue;
            }
            grown.clear();
            for &c in cells {
                let nodes = mesh.cell_nodes(c as usize);
                for a in corners(mesh.degree[c as usize] as usize) {
                    grown.extend_from_slice(patch(nodes[a] as usize));
                }
            }
            grown.sort_unstable();
            grown.dedup();
            if let Some(p) = fit(samples, &grown, mesh.nodes[v], deg_of(&grown)) {
                add(v, &p, cells, Some(&covered), &mut acc, &mut cnt);
            }
        }
    }
    // Last resort: the mean of the finite samples of the node's cells.
    let mut acc2 = vec![[0.0f64; 4]; nn];
    let mut cnt2 = vec![0u32; nn];
    if cnt.contains(&0) {
        for (c, cs) in samples.iter().enumerate().take(nc) {
            if cs.n == 0 {
                continue;
            }
            let mut mean = [0.0; 4];
            for (_, s) in cs.iter() {
                for (m, v) in mean.iter_mut().zip(s) {
                    *m += v / cs.n as f64;
                }
            }
            for &n in mesh.cell_nodes(c) {
                let n = n as usize;
                if cnt[n] == 0 {
                    for (a, b) in acc2[n].iter_mut().zip(mean) {
                        *a += b;
                    }
                    cnt2[n] += 1;
                }
            }
        }
    }
    (0..nn)
        .map(|n| {
            if cnt[n] > 0 {
                acc[n].map(|v| v / f64::from(cnt[n]))
            } else if cnt2[n] > 0 {
                acc2[n].map(|v| v / f64::from(cnt2[n]))
            } else {
                [0.0; 4]
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    const SEED: u64 = 12345;

    /// The next number in [−1, 1) of a small linear congruential generator: reproducible
    /// points without a dependency.
    fn uniform(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    /// Normal equations of the complete cubic (padded as in [`fit`]) on `pts` (scaled to the
    /// unit disc), with the right-hand side of a smooth field, and the rank threshold.
    fn normal(pts: &[Vec2], mask: u16) -> (Normal, Rhs, f64) {
        let mut a = Normal::zeros();
        let mut b = Rhs::zeros();
        for x in pts {
            let phi = monomials(x);
            a += phi * phi.transpose();
            let s = [x[0].sin(), x[1].exp(), x[0] * x[1], 1.0 + x[0] * x[0]];
            b += phi * SMatrix::<f64, 1, 4>::from_row_slice(&s);
        }
        let on = |i: usize| mask & (1 << i) != 0;
        let amax = (0..MAX_TERMS)
            .filter(|&i| on(i))
            .map(|i| a[(i, i)])
            .fold(0.0, f64::max);
        for i in (0..MAX_TERMS).filter(|&i| !on(i)) {
            for j in 0..MAX_TERMS {
                a[(i, j)] = 0.0;
                a[(j, i)] = 0.0;
            }
            a[(i, i)] = 1.0;
            for j in 0..4 {
                b[(i, j)] = 0.0;
            }
        }
        (a, b, 1e-12 * amax)
    }

    /// Random patches, some degenerate (points on one or two lines, or within 1e-7 of a line):
    /// the verdict is the eigenvalues' (smallest one above the threshold or not), and a solved
    /// fit satisfies its normal equations to round-off (backward stable).
    #[test]
    fn fits_are_decided_by_the_smallest_eigenvalue_and_solve_their_equations() {
        let mut seed = SEED;
        let mut next = || uniform(&mut seed);
        let (mut solved, mut singular) = (0, 0);
        for case in 0..600 {
            let n = 1 + case % 17;
            let mut pts: Vec<Vec2> = (0..n).map(|_| Vec2::new(next(), next())).collect();
            match case % 5 {
                1 => pts.iter_mut().for_each(|p| p[1] = 0.3 * p[0] - 0.1),
                2 => pts
                    .iter_mut()
                    .enumerate()
                    .for_each(|(i, p)| p[1] = if i % 2 == 0 { 0.5 } else { -0.2 }),
                3 => pts.iter_mut().for_each(|p| p[1] = 0.3 * p[0] + 1e-7 * p[1]),
                _ => {}
            }
            for &mask in masks(2) {
                let (a, b, thr) = normal(&pts, mask);
                let regular = a.symmetric_eigenvalues().min() > thr;
                match fit_solve(a, &b, thr) {
                    Some(c) => {
                        assert!(regular, "case {case}, mask {mask:b}: solved a singular fit");
                        let res = (a * c - b).norm();
                        let scale = a.norm() * c.norm() + b.norm();
                        assert!(
                            res <= 1e-13 * scale,
                            "case {case}, mask {mask:b}: residual {res:.2e} of {scale:.2e}"
                        );
                        solved += 1;
                    }
                    None => {
                        assert!(
                            !regular,
                            "case {case}, mask {mask:b}: refused a regular fit"
                        );
                        singular += 1;
                    }
                }
            }
        }
        // Both verdicts occur often enough for the comparison to mean something.
        assert!(
            solved > 500 && singular > 500,
            "{solved} solved, {singular} singular"
        );
    }

    /// The fit on a patch where nalgebra's SVD (0.35) loses accuracy: its factors are off by
    /// 5e-3, the Cholesky solution satisfies the equations to round-off.
    #[test]
    fn a_well_conditioned_patch_is_fitted_to_round_off() {
        let mut seed = SEED;
        let mut next = || uniform(&mut seed);
        // Draw the points of case 285 of the test above (the generator's state at that case).
        let mut pts = Vec::new();
        for case in 0..=285 {
            let n = 1 + case % 17;
            pts = (0..n)
                .map(|_| Vec2::new(next(), next()))
                .collect::<Vec<_>>();
        }
        let (a, b, thr) = normal(&pts, 0b11_1111_1111);
        let svd = a.svd(true, true);
        let recomposed = svd.recompose().expect("u and v were asked for");
        let Some(c) = fit_solve(a, &b, thr) else {
            panic!("a regular patch was refused");
        };
        let res = (a * c - b).amax();
        assert!(res < 1e-13 * b.amax(), "residual {res:.2e}");
        // Documents the reason for not using the SVD; if nalgebra fixes it, this line fails and
        // the doc comment of `fit_solve` can drop the remark.
        assert!(
            (recomposed - a).amax() > 1e-6,
            "nalgebra's SVD is accurate here now"
        );
    }
}
