//! Steady transport along the streamlines of rolling on any mesh: upwind discontinuous Galerkin
//! on the quadrature points.
//!
//! # Equations
//!
//! In steady rolling at angular speed ω the material derivative is `ω ∂θ = β·∇` with the rigid
//! rotation field `β = ω (−X₂, X₁)`. An internal variable with relaxation time τ driven by a
//! source `s` obeys the transport–reaction equation
//!
//! ```text
//! β·∇Y + Y/τ = s            on the body, no inflow boundary (β·n = 0 on circles)
//! ```
//!
//! Its unknowns here are the values of `Y` at the quadrature points of the element kernels
//! (q × q Gauss points, q = degree + 1 per cell): in each cell `Y` is the tensor Lagrange
//! polynomial through them, discontinuous between cells. The upwind discontinuous Galerkin
//! scheme, tested with the Lagrange basis `ℓ_k` and integrated with the same Gauss rule
//! (collocated: the mass matrix is diagonal), reads for the point `k` of cell K
//!
//! ```text
//! β·∇Y(X_k) + Y_k/τ + Σ_{inflow faces, β·n < 0} Σ_f w_f |β·n|_f ℓ_k(X_f) (Y⁻ − Y⁺)(X_f) / (w_k J_k) = s_k
//! ```
//!
//! with `Y⁻` the trace of the cell's own polynomial and `Y⁺` the trace of the upwind neighbour's
//! at the q Gauss points `X_f` of the face. The neighbour is found by locating `X_f` just
//! outside the face, so hanging nodes (one big face against two small ones) and unstructured
//! meshes need nothing special; a face point with no cell beyond it (an inflow piece of a
//! polygonal boundary) takes `Y⁺ = Y⁻`. The scheme is exact for constants (a constant source
//! gives `Y = τ s`), of order q in the cell size for smooth fields, and L²-stable (upwinding
//! only adds dissipation). On the built-in annulus, whose cells are exact polar maps, the radial
//! faces carry no flux and the scheme splits into independent rings of points, one 1D upwind
//! scheme per ring.
//!
//! Written `A Y = s` with `A = |ω| T + I/τ` (T for the direction of ω), the matrix is sparse
//! (a cell's points couple to their own cell and to the upwind neighbours) and is factorised
//! once per ω and τ; each right-hand side is then a pair of triangular solves.

use crate::element::quadrature::gauss_1d;
use crate::element::{Lagrange2D, Q1, Q2};
use crate::math::{Mat2, Vec2};
use crate::mesh::locate::{inverse_map, PointLocator};
use crate::mesh::{CellGeometry, Mesh};
use crate::solver::linear::{LinearError, LinearKind, SparseSolver};

/// Why the upwind transport operator could not be built or factorised.
#[derive(Clone, Debug, PartialEq)]
pub enum UpwindError {
    /// Cell `cell` does not carry the q × q tensor Gauss points of its degree.
    NotTensorGauss { cell: usize, points: usize },
    /// Cell `cell` is degenerate at one of its points (non-positive Jacobian).
    Degenerate { cell: usize },
    /// The sparse factorisation failed.
    Linear(String),
}

impl std::fmt::Display for UpwindError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NotTensorGauss { cell, points } => write!(
                f,
                "cell {cell} carries {points} quadrature points, not the q × q Gauss points of \
                 its degree"
            ),
            Self::Degenerate { cell } => {
                write!(
                    f,
                    "cell {cell} has a non-positive Jacobian at a quadrature point"
                )
            }
            Self::Linear(e) => write!(f, "the streamline transport matrix: {e}"),
        }
    }
}

impl From<LinearError> for UpwindError {
    fn from(e: LinearError) -> Self {
        Self::Linear(e.to_string())
    }
}

/// `|ω| τ` (radians of memory) above which [`UpwindTransport::solve`] takes the sparse LU: the
/// block sweep's wrap-around error decays like `exp(−2π/(|ω| τ))` per revolution, so beyond
/// about a third of a revolution of memory the sweeps are slow.
pub const LONG_MEMORY: f64 = 2.0;

/// Matrix products of an iterative solve beyond which the term takes the sparse LU from then
/// on (at that ω).
pub const SLOW_SWEEPS: usize = 60;

/// Lagrange basis through `nodes` at `s`: values into `l`, derivatives into `dl`.
pub(crate) fn lagrange_with_derivative(nodes: &[f64], s: f64, l: &mut [f64], dl: &mut [f64]) {
    let q = nodes.len();
    for i in 0..q {
        let mut v = 1.0;
        let mut d = 0.0;
        for m in 0..q {
            if m == i {
                continue;
            }
            let den = nodes[i] - nodes[m];
            // Product rule: d(v · (s − s_m)/den) = d · (s − s_m)/den + v / den.
            d = d * (s - nodes[m]) / den + v / den;
            v *= (s - nodes[m]) / den;
        }
        l[i] = v;
        dl[i] = d;
    }
}

/// Position and Jacobian ∂X/∂(ξ, η) of cell `c` at (ξ, η): the exact polar map of a polar cell,
/// the isoparametric map otherwise.
fn cell_map(mesh: &Mesh, c: usize, xi: f64, eta: f64) -> (Vec2, Mat2) {
    if let Some(m) = mesh.geometry[c].polar_map(xi, eta) {
        return m;
    }
    let mut n = [0.0; 9];
    let mut dn = [[0.0; 2]; 9];
    let nodes = mesh.cell_nodes(c);
    if mesh.degree[c] == 1 {
        Q1::eval(xi, eta, &mut n[..4], &mut dn[..4]);
    } else {
        Q2::eval(xi, eta, &mut n, &mut dn);
    }
    let mut x = Vec2::zeros();
    let mut j = Mat2::zeros();
    for (a, &node) in nodes.iter().enumerate() {
        let p = mesh.nodes[node as usize];
        x += p * n[a];
        j[(0, 0)] += p[0] * dn[a][0];
        j[(0, 1)] += p[0] * dn[a][1];
        j[(1, 0)] += p[1] * dn[a][0];
        j[(1, 1)] += p[1] * dn[a][1];
    }
    (x, j)
}

/// Reference coordinates of the point `x` in cell `c`: exact for a polar cell (the angle taken
/// on the branch nearest the cell), Newton on the isoparametric map otherwise.
pub(crate) fn reference_of(mesh: &Mesh, c: usize, x: Vec2) -> Option<(f64, f64)> {
    match mesh.geometry[c] {
        CellGeometry::Polar { r0, r1, t0, t1 } => {
            let tm = 0.5 * (t0 + t1);
            let two_pi = 2.0 * std::f64::consts::PI;
            let mut t = x[1].atan2(x[0]) - tm;
            t -= two_pi * (t / two_pi).round();
            Some((2.0 * (x.norm() - r0) / (r1 - r0) - 1.0, 2.0 * t / (t1 - t0)))
        }
        CellGeometry::Isoparametric => inverse_map(mesh, c, x),
    }
}

/// The upwind transport operator of a mesh (see the module docs).
#[derive(Clone)]
pub struct UpwindTransport {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// Values of T in pattern order (β for |ω| = 1 in the direction the operator was built for).
    t: Vec<f64>,
    /// Position of the diagonal entry of each column in the values.
    diag: Vec<usize>,
    /// Points of each cell: `cell_off[c]..cell_off[c + 1]`.
    cell_off: Vec<usize>,
    /// Cells in flow order (by the angle of their centre, downstream from a cut).
    order: Vec<u32>,
    /// T by rows (CSR), for the block sweeps.
    row_ptr: Vec<usize>,
    col_idx: Vec<u32>,
    t_rows: Vec<f64>,
    /// Offset of each cell's dense diagonal block in `block_inv[term]`.
    block_off: Vec<usize>,
    /// Factorisations and scratch of the solves (not cloned).
    work: Solves,
    /// Iterations of the last iterative solve (matrix products), and whether it fell back to
    /// the sparse LU.
    pub last_iterations: usize,
    pub lu_fallbacks: usize,
    /// Flux |β·n| (for |ω| = 1) through inflow face points with no cell beyond them, relative to
    /// the flux through all inflow face points: 0 on the built-in annulus, small (the boundary's
    /// deviation from a circle) on curved meshes.
    pub boundary_inflow: f64,
    forward: bool,
}

impl std::fmt::Debug for UpwindTransport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("UpwindTransport")
            .field("points", &self.n)
            .field("entries", &self.row_idx.len())
            .field("forward", &self.forward)
            .field("boundary_inflow", &self.boundary_inflow)
            .finish()
    }
}

/// The factorisations and scratch of [`UpwindTransport::solve`]; a clone starts empty (they are
/// rebuilt on first use).
#[derive(Default)]
struct Solves {
    /// Per time constant: the inverses of the diagonal blocks `|ω| T_cc + I/τ`, row-major,
    /// valid for `blocks_for`.
    block_inv: Vec<Vec<f64>>,
    blocks_for: Option<(f64, Vec<f64>)>,
    /// Sparse LU per time constant (the fallback when the sweeps converge slowly), valid for
    /// `factored_for`.
    solvers: Vec<SparseSolver>,
    factored_for: Option<(f64, Vec<f64>)>,
    values: Vec<f64>,
    /// Scratch of the iterative solve.
    rhs: Vec<f64>,
    x: Vec<f64>,
    sweep: Vec<f64>,
    /// (|ω| bits, term) whose iterative solve needed more than [`SLOW_SWEEPS`] products.
    slow_terms: Vec<(u64, usize)>,
}

impl Clone for Solves {
    fn clone(&self) -> Self {
        Self::default()
    }
}

impl UpwindTransport {
    /// The operator for the points of `mesh` numbered by `offsets` (cell c owns the points
    /// `offsets[c]..offsets[c + 1]`, q × q Gauss points in tensor order, ξ fastest), for
    /// counter-clockwise flow (`forward`, ω > 0) or clockwise.
    #[allow(
        clippy::needless_range_loop,
        reason = "point k indexes the mass, the tensor factors k % q and k / q and the rows together"
    )]
    pub fn new(mesh: &Mesh, offsets: &[usize], forward: bool) -> Result<Self, UpwindError> {
        let nc = mesh.n_cells();
        let q_of = |c: usize| usize::from(mesh.degree[c]) + 1;
        for c in 0..nc {
            let pts = offsets[c + 1] - offsets[c];
            if pts != q_of(c) * q_of(c) {
                return Err(UpwindError::NotTensorGauss {
                    cell: c,
                    points: pts,
                });
            }
        }
        let n = offsets[nc];
        let sign = if forward { 1.0 } else { -1.0 };
        let beta = |x: Vec2| Vec2::new(-x[1], x[0]) * sign;
        let locator = PointLocator::new(mesh);
        let mut trip: Vec<(usize, usize, f64)> = Vec::with_capacity(n * 24);
        let (mut inflow_all, mut inflow_open) = (0.0, 0.0);
        let mut l = [[0.0; 4]; 2];
        let mut dl = [[0.0; 4]; 2];
        let mut ln = [[0.0; 4]; 2];
        let mut scratch = [0.0; 4];
        for c in 0..nc {
            let q = q_of(c);
            let (g, w) = gauss_1d(q);
            let off = offsets[c];
            // w_k J_k of each point (the collocated mass).
            let mut mass = [0.0; 16];
            // Volume terms: β·∇ℓ_j at each point k.
            for k in 0..q * q {
                let (ik, lk) = (k % q, k / q);
                let (x, jac) = cell_map(mesh, c, g[ik], g[lk]);
                let det = jac.determinant();
                let inv = jac
                    .try_inverse()
                    .filter(|_| det > 0.0)
                    .ok_or(UpwindError::Degenerate { cell: c })?;
                mass[k] = w[ik] * w[lk] * det;
                // Reference direction of β: inv · β (a component at round-off level, e.g. the
                // radial one in a polar cell, is zero: it would only widen the pattern).
                let bref = inv * beta(x);
                let bmax = bref.amax();
                let bref = bref.map(|v| if v.abs() < 1e-13 * bmax { 0.0 } else { v });
                lagrange_with_derivative(&g, g[ik], &mut l[0][..q], &mut dl[0][..q]);
                lagrange_with_derivative(&g, g[lk], &mut l[1][..q], &mut dl[1][..q]);
                trip.push((off + k, off + k, 0.0));
                for j in 0..q * q {
                    let (ij, lj) = (j % q, j / q);
                    let d = bref[0] * dl[0][ij] * l[1][lj] + bref[1] * l[0][ij] * dl[1][lj];
                    if d != 0.0 {
                        trip.push((off + k, off + j, d));
                    }
                }
            }
            // Faces: (axis, side); axis 0 is ξ = side, axis 1 is η = side.
            for (axis, side) in [(0, -1.0), (0, 1.0), (1, -1.0), (1, 1.0)] {
                for (&s, &wf) in g.iter().zip(&w) {
                    let (xi, eta) = if axis == 0 { (side, s) } else { (s, side) };
                    let (x, jac) = cell_map(mesh, c, xi, eta);
                    let det = jac.determinant();
                    let Some(inv) = jac.try_inverse() else {
                        return Err(UpwindError::Degenerate { cell: c });
                    };
                    // n dS = det J · J⁻ᵀ e_axis · side · w_f.
                    let nds = inv.transpose().column(axis) * (det * side * wf);
                    let bn = beta(x).dot(&nds);
                    if bn >= 0.0 {
                        continue;
                    }
                    inflow_all += -bn;
                    // Own trace weights at the face point.
                    lagrange_with_derivative(&g, xi, &mut ln[0][..q], &mut scratch[..q]);
                    lagrange_with_derivative(&g, eta, &mut ln[1][..q], &mut scratch[..q]);
                    // The upwind neighbour: the cell holding a point just outside the face.
                    let size = det.abs().sqrt();
                    let out = x + nds.normalize() * (1e-7 * size.max(1e-300));
                    let nb = locator
                        .locate(mesh, out)
                        .map(|(cn, _, _)| cn)
                        .filter(|&cn| cn != c)
                        .and_then(|cn| reference_of(mesh, cn, x).map(|r| (cn, r)));
                    let Some((cn, (xn, en))) = nb else {
                        inflow_open += -bn;
                        continue;
                    };
                    let qn = q_of(cn);
                    let (gn, _) = gauss_1d(qn);
                    let mut lnb = [[0.0; 4]; 2];
                    lagrange_with_derivative(&gn, xn, &mut lnb[0][..qn], &mut scratch[..qn]);
                    lagrange_with_derivative(&gn, en, &mut lnb[1][..qn], &mut scratch[..qn]);
                    // Weights at round-off level (a face point at a Gauss abscissa of the
                    // neighbour, located to 1e-16) are zeros.
                    for v in lnb.iter_mut().flat_map(|r| r.iter_mut()) {
                        if v.abs() < 1e-12 {
                            *v = 0.0;
                        }
                    }
                    let offn = offsets[cn];
                    for k in 0..q * q {
                        let lk = ln[0][k % q] * ln[1][k / q];
                        if lk == 0.0 {
                            continue;
                        }
                        let kappa = -bn * lk / mass[k];
                        for j in 0..q * q {
                            let v = kappa * ln[0][j % q] * ln[1][j / q];
                            if v != 0.0 {
                                trip.push((off + k, off + j, v));
                            }
                        }
                        for j in 0..qn * qn {
                            let v = -kappa * lnb[0][j % qn] * lnb[1][j / qn];
                            if v != 0.0 {
                                trip.push((off + k, offn + j, v));
                            }
                        }
                    }
                }
            }
        }
        // Triplets → CSC (columns, rows sorted, duplicates summed).
        trip.sort_unstable_by_key(|&(r, c, _)| (c, r));
        let mut col_ptr = vec![0usize; n + 1];
        let mut row_idx = Vec::with_capacity(trip.len());
        let mut t = Vec::with_capacity(trip.len());
        let mut diag = vec![usize::MAX; n];
        let mut last = (usize::MAX, usize::MAX);
        for &(r, c, v) in &trip {
            if (r, c) == last {
                if let Some(tv) = t.last_mut() {
                    *tv += v;
                }
                continue;
            }
            last = (r, c);
            if r == c {
                diag[c] = row_idx.len();
            }
            row_idx.push(r);
            t.push(v);
            col_ptr[c + 1] = row_idx.len();
        }
        for c in 0..n {
            col_ptr[c + 1] = col_ptr[c + 1].max(col_ptr[c]);
        }
        // CSR copy for the block sweeps.
        let mut row_ptr = vec![0usize; n + 1];
        for &r in &row_idx {
            row_ptr[r + 1] += 1;
        }
        for i in 0..n {
            row_ptr[i + 1] += row_ptr[i];
        }
        let mut fill = row_ptr.clone();
        let mut col_idx = vec![0u32; row_idx.len()];
        let mut t_rows = vec![0.0; row_idx.len()];
        for c in 0..n {
            for p in col_ptr[c]..col_ptr[c + 1] {
                let r = row_idx[p];
                col_idx[fill[r]] = c as u32;
                t_rows[fill[r]] = t[p];
                fill[r] += 1;
            }
        }
        // Flow order: cells by the angle of their centre, increasing for counter-clockwise
        // flow, from the cut at θ = π.
        let mut keyed: Vec<(f64, u32)> = (0..nc)
            .map(|c| {
                let (x, _) = cell_map(mesh, c, 0.0, 0.0);
                (sign * x[1].atan2(x[0]), c as u32)
            })
            .collect();
        keyed.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut block_off = vec![0usize; nc + 1];
        for c in 0..nc {
            let m = offsets[c + 1] - offsets[c];
            block_off[c + 1] = block_off[c] + m * m;
        }
        Ok(Self {
            n,
            col_ptr,
            row_idx,
            t,
            diag,
            cell_off: offsets[..=nc].to_vec(),
            order: keyed.into_iter().map(|(_, c)| c).collect(),
            row_ptr,
            col_idx,
            t_rows,
            block_off,
            work: Solves::default(),
            last_iterations: 0,
            lu_fallbacks: 0,
            boundary_inflow: if inflow_all > 0.0 {
                inflow_open / inflow_all
            } else {
                0.0
            },
            forward,
        })
    }

    /// Number of points (unknowns per component).
    pub fn n_points(&self) -> usize {
        self.n
    }

    /// Entries of the sparse operator.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// The flow direction the operator was built for (counter-clockwise: ω > 0).
    pub fn forward(&self) -> bool {
        self.forward
    }

    /// Factorise `|ω| T + I/τ_i` for every time constant (kept until ω or the τ change).
    fn factor(&mut self, omega: f64, taus: &[f64]) -> Result<(), UpwindError> {
        let w = omega.abs();
        if let Some((o, t)) = &self.work.factored_for {
            if *o == w && t.as_slice() == taus {
                return Ok(());
            }
        }
        self.work.factored_for = None;
        if self.work.solvers.len() != taus.len() {
            self.work.solvers.clear();
            for _ in taus {
                self.work.solvers.push(SparseSolver::new(
                    self.n,
                    &self.col_ptr,
                    &self.row_idx,
                    LinearKind::Lu,
                )?);
            }
        }
        for (solver, &tau) in self.work.solvers.iter_mut().zip(taus) {
            self.work.values.clear();
            self.work.values.extend(self.t.iter().map(|v| v * w));
            for &d in &self.diag {
                self.work.values[d] += 1.0 / tau;
            }
            solver.factorize(&self.work.values)?;
        }
        self.work.factored_for = Some((w, taus.to_vec()));
        Ok(())
    }

    /// Invert the diagonal blocks `|ω| T_cc + I/τ_i` of every cell for every time constant.
    fn factor_blocks(&mut self, omega: f64, taus: &[f64]) -> Result<(), UpwindError> {
        let w = omega.abs();
        if let Some((o, t)) = &self.work.blocks_for {
            if *o == w && t.as_slice() == taus {
                return Ok(());
            }
        }
        self.work.blocks_for = None;
        let nc = self.cell_off.len() - 1;
        self.work.block_inv.resize(taus.len(), Vec::new());
        for (inv, &tau) in self.work.block_inv.iter_mut().zip(taus) {
            inv.clear();
            inv.resize(self.block_off[nc], 0.0);
            for c in 0..nc {
                let (lo, hi) = (self.cell_off[c], self.cell_off[c + 1]);
                let m = hi - lo;
                let mut a = nalgebra::DMatrix::<f64>::zeros(m, m);
                for i in lo..hi {
                    a[(i - lo, i - lo)] = 1.0 / tau;
                    for p in self.row_ptr[i]..self.row_ptr[i + 1] {
                        let j = self.col_idx[p] as usize;
                        if (lo..hi).contains(&j) {
                            a[(i - lo, j - lo)] += w * self.t_rows[p];
                        }
                    }
                }
                let ai = a
                    .try_inverse()
                    .ok_or_else(|| UpwindError::Linear(format!("singular block of cell {c}")))?;
                let dst = &mut inv[self.block_off[c]..self.block_off[c + 1]];
                for i in 0..m {
                    for j in 0..m {
                        dst[i * m + j] = ai[(i, j)];
                    }
                }
            }
        }
        self.work.blocks_for = Some((w, taus.to_vec()));
        Ok(())
    }

    /// Solve `(|ω| T + I/τ_i) Y = s` in place (`s` per point), for the time constant `term` of
    /// `taus`. ω = 0 gives `Y = τ s`. GMRES on the sparse operator, preconditioned with one
    /// block sweep in flow order (for a memory shorter than a revolution, |ω| τ ≪ 2π, one
    /// sweep is nearly the solution), to a relative residual of 1e-13; should it not get
    /// there in 200 products, the sparse LU of the operator.
    pub fn solve(
        &mut self,
        omega: f64,
        taus: &[f64],
        term: usize,
        s: &mut [f64],
    ) -> Result<(), UpwindError> {
        if omega == 0.0 {
            s.iter_mut().for_each(|v| *v *= taus[term]);
            return Ok(());
        }
        let w = omega.abs();
        // A memory longer than a third of a revolution, or a term whose sweeps were slow at
        // this ω: the sparse LU.
        if w * taus[term] > LONG_MEMORY || self.work.slow_terms.contains(&(w.to_bits(), term)) {
            self.last_iterations = 0;
            return self.solve_direct(omega, taus, term, s);
        }
        self.factor_blocks(omega, taus)?;
        let inv_tau = 1.0 / taus[term];
        let mut rhs = std::mem::take(&mut self.work.rhs);
        rhs.clear();
        rhs.extend_from_slice(s);
        let mut x = std::mem::take(&mut self.work.x);
        x.clear();
        x.resize(self.n, 0.0);
        let mut scratch = std::mem::take(&mut self.work.sweep);
        let stats = {
            let this = &mut *self;
            let (col_ptr, row_idx, t) = (&this.col_ptr, &this.row_idx, &this.t);
            let apply = |v: &[f64], y: &mut [f64]| {
                for (yi, vi) in y.iter_mut().zip(v) {
                    *yi = inv_tau * vi;
                }
                for (c, &vc) in v.iter().enumerate() {
                    if vc != 0.0 {
                        for p in col_ptr[c]..col_ptr[c + 1] {
                            y[row_idx[p]] += w * t[p] * vc;
                        }
                    }
                }
            };
            // The preconditioner needs `this` mutably (its sweep scratch): a separate copy of
            // what it reads keeps the borrows apart.
            let mut pre = BlockSweep {
                order: &this.order,
                cell_off: &this.cell_off,
                row_ptr: &this.row_ptr,
                col_idx: &this.col_idx,
                t_rows: &this.t_rows,
                block_off: &this.block_off,
                inv: &this.work.block_inv[term],
                y: &mut scratch,
                w,
            };
            crate::solver::krylov::gmres_with(
                apply,
                |z: &mut [f64]| -> Result<(), UpwindError> {
                    pre.apply(z);
                    Ok(())
                },
                &rhs,
                &mut x,
                1e-13,
                40,
                200,
            )?
        };
        self.work.sweep = scratch;
        self.last_iterations = stats.iterations;
        if stats.iterations > SLOW_SWEEPS {
            self.work.slow_terms.push((w.to_bits(), term));
        }
        if stats.rel_residual.is_finite() && stats.rel_residual <= 1e-12 {
            s.copy_from_slice(&x);
        } else {
            self.lu_fallbacks += 1;
            self.solve_direct(omega, taus, term, s)?;
        }
        self.work.rhs = rhs;
        self.work.x = x;
        Ok(())
    }

    /// As [`Self::solve`], always by the sparse LU of the operator.
    pub fn solve_direct(
        &mut self,
        omega: f64,
        taus: &[f64],
        term: usize,
        s: &mut [f64],
    ) -> Result<(), UpwindError> {
        if omega == 0.0 {
            s.iter_mut().for_each(|v| *v *= taus[term]);
            return Ok(());
        }
        self.factor(omega, taus)?;
        self.work.solvers[term].solve_in_place(s)?;
        Ok(())
    }

    /// `T v` (for tests: the transport operator applied to point values).
    pub fn apply_transport(&self, v: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|o| *o = 0.0);
        for (c, &vc) in v.iter().enumerate().take(self.n) {
            for p in self.col_ptr[c]..self.col_ptr[c + 1] {
                out[self.row_idx[p]] += self.t[p] * vc;
            }
        }
    }
}

/// The block Gauss–Seidel sweep of [`UpwindTransport::solve`]: `z ← P⁻¹ z` with P the block
/// lower-triangular part of `|ω| T + I/τ` in flow order, i.e. one sweep from zero, downstream
/// cell by cell (exact but for the flow that crosses the cut, and for faces whose upwind cell
/// comes later in the angular order).
struct BlockSweep<'a> {
    order: &'a [u32],
    cell_off: &'a [usize],
    row_ptr: &'a [usize],
    col_idx: &'a [u32],
    t_rows: &'a [f64],
    block_off: &'a [usize],
    inv: &'a [f64],
    y: &'a mut Vec<f64>,
    w: f64,
}

impl BlockSweep<'_> {
    fn apply(&mut self, z: &mut [f64]) {
        let y = &mut *self.y;
        y.clear();
        y.resize(z.len(), 0.0);
        let mut acc = [0.0; 16];
        for &c in self.order {
            let c = c as usize;
            let (lo, hi) = (self.cell_off[c], self.cell_off[c + 1]);
            for i in lo..hi {
                let mut a = z[i];
                for p in self.row_ptr[i]..self.row_ptr[i + 1] {
                    let j = self.col_idx[p] as usize;
                    if !(lo..hi).contains(&j) {
                        a -= self.w * self.t_rows[p] * y[j];
                    }
                }
                acc[i - lo] = a;
            }
            let m = hi - lo;
            let b = &self.inv[self.block_off[c]..self.block_off[c + 1]];
            for i in 0..m {
                y[lo + i] = (0..m).map(|j| b[i * m + j] * acc[j]).sum();
            }
        }
        z.copy_from_slice(y);
    }
}
