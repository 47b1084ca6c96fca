//! Moving-mesh (r-) adaptivity: the nodes of a uniform quadtree mesh are relocated (same cells,
//! same connectivity, same dofs) to equidistribute a monitor built from the discrete solution,
//! and the problem is solved again on the moved (bilinear) cells, N times.
//!
//! Mesh equation. The vertices form an (n + 1)² logical grid with coordinates ξ. The moved
//! vertices x(ξ) solve the monitor-weighted Laplace equation in logical space (the
//! Euler–Lagrange equation of the variational mesh energy ½ ∫ w |∇_ξ x|² dξ):
//! ∇_ξ · (w ∇_ξ x) = 0, discretised by the five-point stencil with edge weights w_e: every
//! interior vertex is the w-weighted mean of its four neighbours, a boundary vertex the weighted
//! mean of its two neighbours along its edge in the tangential coordinate only (it slides
//! along the edge), the corners are fixed. In 1D this is w x_ξ = const: the cell size is
//! proportional to 1/w, the monitor is equidistributed. The edge weight is
//! w_e = (1 − γ) M(x_e) + γ M̄, with x_e the current edge midpoint, M̄ the mean of M over
//! the cells and M the monitor, a physical field (piecewise constant on the cells of the mesh
//! the solution lives on, located at the moving midpoints in every sweep):
//!
//! M = 1 + α ê^(1/β), ê_K = |∇u|_K / max_K |∇u|_K ∈ [0, 1],
//!
//! with |∇u|_K the Frobenius norm of the velocity gradient at the centre of cell K.
//! * α ≥ 0: monitor amplitude, the largest ratio of monitor values is 1 + α, so cells shrink
//!   by at most that factor along a grid line (α = 0: no motion).
//! * β ≥ 1: root of the normalised indicator, spreading the monitor away from its maximum
//!   (β = 1 linear in the indicator; larger β flattens it, so the refined region is wider).
//! * γ ∈ [0, 1]: weight of the uniform (plain Laplace, smoothness) part of the edge weights;
//!   γ = 0 none, γ = 1 no adaptation.
//!
//! Defaults α = 4, β = 4, γ = 0, 60 Gauss–Seidel sweeps per relocation.
//!
//! Validity. After the sweeps the relocation x_old + λ (x_new − x_old) is taken with λ = 1,
//! halved (at most 30 times) until every cell has det J > 0 at its four corners, which for a
//! bilinear cell bounds det J from below over the whole cell; if no step keeps the mesh valid,
//! [`MovingMeshError::Tangled`].
//!
//! Alternation ([`moving_mesh_cavity`]): solve → indicator → relocate → transfer → solve, the
//! transfer interpolating the old velocity and pressure at the new node positions (located in
//! the old cells) as the Newton initial guess.

use super::navier_stokes::{
    bilinear, min_det_corners, solve_newton, unit_square, CavityLid, CellCorners, NsError,
    TaylorHood,
};

/// Error of the moving-mesh driver.
#[derive(Debug, thiserror::Error)]
pub enum MovingMeshError {
    #[error(transparent)]
    Ns(#[from] NsError),
    #[error("node relocation needs a uniform mesh of squares (no hanging nodes)")]
    NotUniform,
    #[error("bad monitor parameters: need alpha >= 0, beta >= 1 and gamma in [0, 1], got alpha = {alpha}, beta = {beta}, gamma = {gamma}")]
    Parameters { alpha: f64, beta: f64, gamma: f64 },
    #[error("no relocation step keeps the mesh valid: min det J = {det:e} in cell {cell} after 30 halvings")]
    Tangled { cell: usize, det: f64 },
}

/// Monitor and mesh-equation parameters (see the module docs).
#[derive(Clone, Copy, Debug)]
pub struct MonitorParams {
    pub alpha: f64,
    pub beta: f64,
    pub gamma: f64,
    /// Gauss–Seidel sweeps of the mesh equation per relocation.
    pub sweeps: usize,
}

impl Default for MonitorParams {
    fn default() -> Self {
        Self {
            alpha: 4.0,
            beta: 4.0,
            gamma: 0.0,
            sweeps: 60,
        }
    }
}

impl MonitorParams {
    /// α ≥ 0, β ≥ 1 (both finite) and γ ∈ [0, 1], or the error naming them.
    pub fn check(&self) -> Result<(), MovingMeshError> {
        let ok = self.alpha >= 0.0
            && self.alpha.is_finite()
            && self.beta >= 1.0
            && self.beta.is_finite()
            && (0.0..=1.0).contains(&self.gamma);
        if ok {
            Ok(())
        } else {
            Err(MovingMeshError::Parameters {
                alpha: self.alpha,
                beta: self.beta,
                gamma: self.gamma,
            })
        }
    }
}

/// The vertex grid of a uniform mesh: n × n cells, (n + 1)² vertices (index i + (n + 1) j).
#[derive(Clone, Debug)]
pub struct VertexGrid {
    pub n: usize,
    pub x: Vec<[f64; 2]>,
    /// Logical cell (i, j) of each leaf (leaf order of the spaces).
    pub cell_ij: Vec<(usize, usize)>,
}

impl VertexGrid {
    /// The grid of the current corners of `th`, whose tree must be uniform on one square root.
    pub fn new(th: &TaylorHood) -> Result<Self, MovingMeshError> {
        let tree = &th.tree;
        let leaves = &th.vel.leaves;
        let level = tree.cells[leaves[0] as usize].level;
        let n = 1usize << level;
        if leaves.len() != n * n
            || leaves
                .iter()
                .any(|&c| tree.cells[c as usize].level != level)
        {
            return Err(MovingMeshError::NotUniform);
        }
        let h = tree.h(leaves[0]);
        let mut x = vec![[0.0; 2]; (n + 1) * (n + 1)];
        let mut cell_ij = Vec::with_capacity(leaves.len());
        for (k, &c) in leaves.iter().enumerate() {
            let [x0, y0] = tree.corner(c);
            let i = ((x0 - tree.origin[0]) / h).round() as usize;
            let j = ((y0 - tree.origin[1]) / h).round() as usize;
            if i >= n || j >= n {
                return Err(MovingMeshError::NotUniform);
            }
            cell_ij.push((i, j));
            for (a, p) in th.corners[k].iter().enumerate() {
                x[(i + a % 2) + (n + 1) * (j + a / 2)] = *p;
            }
        }
        Ok(Self { n, x, cell_ij })
    }

    /// Corners of every leaf from the vertex positions.
    pub fn corners(&self) -> Vec<CellCorners> {
        let m = self.n + 1;
        self.cell_ij
            .iter()
            .map(|&(i, j)| {
                [
                    self.x[i + m * j],
                    self.x[i + 1 + m * j],
                    self.x[i + m * (j + 1)],
                    self.x[i + 1 + m * (j + 1)],
                ]
            })
            .collect()
    }

    /// Smallest corner det J over all cells and the cell where it occurs.
    pub fn min_det(&self) -> (f64, usize) {
        let mut m = (f64::INFINITY, 0);
        for (k, c) in self.corners().iter().enumerate() {
            let d = min_det_corners(c);
            if d < m.0 {
                m = (d, k);
            }
        }
        m
    }

    /// Relocate the vertices for the monitor `m(x)` (physical field, `gamma` and `sweeps` of
    /// `params` used; `mean` is M̄): the mesh equation of the module docs, then the step
    /// back-off keeping every det J > 0. Returns the accepted step λ.
    pub fn relocate(
        &mut self,
        m: &dyn Fn([f64; 2]) -> f64,
        mean: f64,
        params: &MonitorParams,
    ) -> Result<f64, MovingMeshError> {
        params.check()?;
        let n = self.n;
        let s = n + 1;
        let old = self.x.clone();
        let mut x = self.x.clone();
        let g = params.gamma;
        let w = |a: [f64; 2], b: [f64; 2]| {
            (1.0 - g) * m([0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])]) + g * mean
        };
        for _ in 0..params.sweeps {
            for j in 0..=n {
                for i in 0..=n {
                    let id = i + s * j;
                    let p = x[id];
                    let bi = i == 0 || i == n;
                    let bj = j == 0 || j == n;
                    if bi && bj {
                        continue;
                    }
                    let mut nb: [Option<usize>; 4] = [None; 4];
                    if !bj {
                        nb[0] = Some(id - s);
                        nb[1] = Some(id + s);
                    }
                    if !bi {
                        nb[2] = Some(id - 1);
                        nb[3] = Some(id + 1);
                    }
                    let (mut sw, mut sx) = (0.0, [0.0; 2]);
                    for q in nb.into_iter().flatten() {
                        let we = w(p, x[q]);
                        sw += we;
                        sx[0] += we * x[q][0];
                        sx[1] += we * x[q][1];
                    }
                    if sw.is_nan() || sw <= 0.0 {
                        continue;
                    }
                    // Interior: both coordinates; left/right edges: y only; bottom/top: x only.
                    if !bi {
                        x[id][0] = sx[0] / sw;
                    }
                    if !bj {
                        x[id][1] = sx[1] / sw;
                    }
                }
            }
        }
        let mut lambda = 1.0;
        for _ in 0..=30 {
            for (v, (&a, &b)) in self.x.iter_mut().zip(old.iter().zip(&x)) {
                *v = [a[0] + lambda * (b[0] - a[0]), a[1] + lambda * (b[1] - a[1])];
            }
            if self.min_det().0 > 0.0 {
                return Ok(lambda);
            }
            lambda *= 0.5;
        }
        let (det, cell) = self.min_det();
        self.x = old;
        Err(MovingMeshError::Tangled { cell, det })
    }
}

/// Cell monitor values M_K = 1 + α ê_K^(1/β) of the velocity in `x` (full dof vector) on `th`.
pub fn cell_monitor(th: &TaylorHood, x: &[f64], params: &MonitorParams) -> Vec<f64> {
    let e: Vec<f64> = (0..th.vel.leaves.len())
        .map(|k| {
            let (_, gu) = th.eval_velocity(x, k, 0, 0.0, 0.0);
            let (_, gv) = th.eval_velocity(x, k, 1, 0.0, 0.0);
            (gu[0] * gu[0] + gu[1] * gu[1] + gv[0] * gv[0] + gv[1] * gv[1]).sqrt()
        })
        .collect();
    let emax = e.iter().fold(0.0f64, |a, &b| a.max(b));
    e.iter()
        .map(|&v| {
            let eh = if emax > 0.0 { v / emax } else { 0.0 };
            1.0 + params.alpha * eh.powf(1.0 / params.beta)
        })
        .collect()
}

/// Full dof vector on `th` with the new `corners`, interpolating the field `x` of `th` (with its
/// current corners) at the new positions of the velocity and pressure nodes.
fn transfer(th: &TaylorHood, x: &[f64], corners: &[CellCorners]) -> Vec<f64> {
    let mut out = x.to_vec();
    let r = [-1.0, 1.0, 0.0];
    for (k, c) in corners.iter().enumerate() {
        let vd = th.vel.dofs(k);
        for a in 0..9 {
            let p = bilinear(c, r[a % 3], r[a / 3]).0;
            if let Some((kk, xi, eta)) = th.locate(p) {
                for comp in 0..2 {
                    out[vd[2 * a + comp] as usize] = th.eval_velocity(x, kk, comp, xi, eta).0;
                }
            }
        }
        let pd = th.pres.dofs(k);
        for b in 0..4 {
            let p = bilinear(c, r[b % 2], r[b / 2]).0;
            if let Some((kk, xi, eta)) = th.locate(p) {
                out[th.n_u + pd[b] as usize] = th.eval_pressure(x, kk, xi, eta);
            }
        }
    }
    out
}

/// One recalculation of [`moving_mesh_cavity`].
#[derive(Clone, Debug)]
pub struct Recalculation {
    /// 0: the starting uniform mesh.
    pub index: usize,
    /// Reynolds number of the solution (the last of the continuation, or the one it reached).
    pub reynolds: f64,
    /// Smallest det J over the cells (corners and Gauss points).
    pub min_det_j: f64,
    /// Accepted relocation step λ (1 for the starting mesh).
    pub step: f64,
    pub newton_iterations: usize,
}

/// The lid-driven cavity on the uniform 2^levels × 2^levels mesh, solved by continuation over
/// `reynolds`, then `recalculations` times: monitor → relocate → transfer → Newton at the last
/// Reynolds number. `each(recalculation, th, x)` sees every converged solution (full dofs).
pub fn moving_mesh_cavity(
    levels: u32,
    lid: CavityLid,
    reynolds: &[f64],
    params: &MonitorParams,
    recalculations: usize,
    tol: f64,
    each: &mut dyn FnMut(&Recalculation, &TaylorHood, &[f64]),
) -> Result<(TaylorHood, Vec<f64>), MovingMeshError> {
    let run = moving_mesh_cavity_until(
        levels,
        lid,
        reynolds,
        params,
        recalculations,
        tol,
        &|| false,
        each,
    )?;
    Ok((run.th, run.x))
}

/// What [`moving_mesh_cavity_until`] computed.
pub struct CavityRun {
    pub th: TaylorHood,
    /// The last converged solution (full dofs).
    pub x: Vec<f64>,
    /// The Reynolds number of that solution (the last of the ladder unless stopped before).
    pub reynolds: f64,
    /// Whether `stop` ended the run early.
    pub stopped: bool,
}

/// [`moving_mesh_cavity`], polling `stop()` after every Newton solve of the continuation and
/// every recalculation: when it is true the run ends there (after `each` has seen the solution
/// reached).
#[allow(clippy::too_many_arguments)]
pub fn moving_mesh_cavity_until(
    levels: u32,
    lid: CavityLid,
    reynolds: &[f64],
    params: &MonitorParams,
    recalculations: usize,
    tol: f64,
    stop: &dyn Fn() -> bool,
    each: &mut dyn FnMut(&Recalculation, &TaylorHood, &[f64]),
) -> Result<CavityRun, MovingMeshError> {
    params.check()?;
    let tree = unit_square(levels);
    let mut th = TaylorHood::new(&tree, &|x, c| lid.g(x, c))?;
    let zero = |_: [f64; 2]| [0.0, 0.0];
    let mut y = vec![0.0; th.n_eq()];
    let mut its = 0;
    let mut re = 1.0;
    let mut stopped = false;
    for (i, &r) in reynolds.iter().enumerate() {
        its += solve_newton(&th, &mut y, 1.0 / r, &zero, tol, 30)?.iterations;
        re = r;
        if i + 1 < reynolds.len() && stop() {
            stopped = true;
            break;
        }
    }
    let mut x = th.distribute(&y);
    let rec = Recalculation {
        index: 0,
        reynolds: re,
        min_det_j: th.min_det_j(),
        step: 1.0,
        newton_iterations: its,
    };
    each(&rec, &th, &x);
    let mut grid = VertexGrid::new(&th)?;
    for index in 1..=recalculations {
        if stopped || stop() {
            stopped = true;
            break;
        }
        let mk = cell_monitor(&th, &x, params);
        let area: f64 = th
            .corners
            .iter()
            .map(|c| bilinear(c, 0.0, 0.0).2 * 4.0)
            .sum();
        let mean = th
            .corners
            .iter()
            .zip(&mk)
            .map(|(c, &m)| m * bilinear(c, 0.0, 0.0).2 * 4.0)
            .sum::<f64>()
            / area;
        let monitor = |p: [f64; 2]| match th.locate(p) {
            Some((k, _, _)) => mk[k],
            None => mean,
        };
        let step = grid.relocate(&monitor, mean, params)?;
        let corners = grid.corners();
        let xt = transfer(&th, &x, &corners);
        th.set_corners(corners)?;
        y = th.gather(&xt);
        let st = solve_newton(&th, &mut y, 1.0 / re, &zero, tol, 30)?;
        x = th.distribute(&y);
        let rec = Recalculation {
            index,
            reynolds: re,
            min_det_j: th.min_det_j(),
            step,
            newton_iterations: st.iterations,
        };
        each(&rec, &th, &x);
    }
    Ok(CavityRun {
        th,
        x,
        reynolds: re,
        stopped,
    })
}
