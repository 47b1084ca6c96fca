//! diffsol's BDF and SDIRK integrators on the first-order form of the transient model
//! ([`super`]): with y = (u, v) over the **free** displacement dofs,
//!
//! ```text
//!   u̇ = v
//!   M_ff v̇ = −f_f(u, v, t) − M_fh a_h(t)
//! ```
//!
//! i.e. B ẏ = F(y, t) with B = diag(I, M_ff) (consistent or HRZ-lumped mass, see
//! [`Transient`]) and F = (v, −R), R = f_int + f_c + M_fh a_h the dynamic residual of the
//! free rows with zero free acceleration.
//!
//! * **Prescribed hub.** The hub dofs are not unknowns: their position Q(φ(t))X − X, velocity
//!   ω e3 × x and acceleration (ω̇ e3 × x − ω² x) are exact functions of t (the same smoothstep
//!   ramps as for generalized-α), and enter F as a time-dependent forcing: through the
//!   internal and damping forces of the cells next to the hub, and, with the consistent mass,
//!   through the inertia coupling M_fh a_h(t). The road height (or load), and the road speed
//!   enter the same way. Nothing is approximated: the first-order system is exact for the
//!   free dofs.
//! * **Jacobian** ∂F/∂y = [[0, I], [−K, −C]], K = ∂R/∂u, C = ∂R/∂v, supplied with an explicit
//!   sparsity (the assembler's free-dof pattern for both lower blocks, the identity for the
//!   upper right one), assembled from two evaluations of the existing dynamic kernel
//!   (kv = 0 gives K; kv = 1 gives K + C). The mass B gets the identity plus the same pattern.
//!   diffsol forms and LU-factorises B − hγ J itself (2n unknowns, unsymmetric).
//! * **Error control** is diffsol's own (BDF: variable order 1–5, its predictor–corrector
//!   estimate; SDIRK: the embedded pair of the tableau), on both u and v, with the mixed norm
//!   ‖e_i / (atol_i + rtol |y_i|)‖_rms ≤ 1. Mapping from the scene ([`OdeTolerances::from_scene`]):
//!   rtol = `time.error_tol`; atol_u = `error_tol` · 10⁻² R_o (a length: 1 % of the outer
//!   radius); atol_v = atol_u · ω_ref with ω_ref = ω (the hub speed) or 2π / t_end without spin.
//!   This is a different quantity from the generalized-α estimate (a local error relative to the
//!   step increment), so equal `error_tol` values do not give equal accuracy across integrators.
//!   `time.dt` is the first step; `time.dt_min` is diffsol's minimum step; `time.dt_max` and
//!   `time.adaptive` are not used (diffsol always adapts; it has no maximum step).
//! * **Output times.** After every accepted step the driver's state (t, u_n, v_n, a_n of the
//!   full vectors, hub dofs from the kinematics) is filled from diffsol's and the caller's
//!   `on_step` runs, as for generalized-α. Once the ramps are done, diffsol's stop time is set to
//!   the next node passage (φ(t) = kΔθ, the same bisection as the generalized-α driver), so every
//!   passage is a computed state and [`SteadyMonitor`] sees exactly what it sees with
//!   generalized-α (landing on passages); `time.t_end` is a stop time too.
//! * **Failures** (diffsol errors, step-size collapse, a panic inside diffsol such as a failed
//!   sparse LU) end the run with [`SolveError::Integrator`]; the driver's state is the last
//!   accepted step, so everything recorded so far stays valid.
//! * **Viscoelastic history.** The internal variables at the quadrature points are not states of
//!   the ODE: like the one-step integrators, every evaluation at time t takes the overstress over
//!   the step from the last accepted time t_n to t (exact for a strain linear in time over that
//!   step), and each accepted step commits the history. Within a step F(t, y) is smooth; the
//!   history is a second-order accurate splitting, so with a viscoelastic material the higher
//!   orders of BDF and SDIRK are not reached in the overstress.
//! * Limits: pure displacement models only (no cell pressures, no load-control road unknown):
//!   those make the system differential-algebraic; the function returns a clear error instead.
//! * Subnormal floats slowed diffsol's sparse solves 8–12× in decaying dynamics (measured):
//!   the integration runs with flush-to-zero / denormals-are-zero set on the calling thread
//!   (restored afterwards).

use super::{SteadyMonitor, TimeOptions, Transient, TransientReport};
use crate::assembly::CONSTRAINED;
use crate::solver::SolveError;
use diffsol::op::unit::UnitCallable;
use diffsol::op::ParameterisedOp;
use diffsol::{
    ConstantOp, FaerContext, FaerSparseLU, FaerSparseMat, FaerVec, LinearOp, Matrix, NonLinearOp,
    NonLinearOpJacobian, OdeBuilder, OdeEquations, OdeEquationsRef, OdeSolverMethod,
    OdeSolverProblem, OdeSolverStopReason, Op, Vector, VectorCommon,
};
use faer::sparse::SymbolicSparseColMat;
use std::cell::RefCell;
use std::f64::consts::PI;
use std::panic::{catch_unwind, AssertUnwindSafe};

type M = FaerSparseMat<f64>;
type V = FaerVec<f64>;
type LS = FaerSparseLU<f64>;

/// diffsol integrator on the first-order form.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OdeMethod {
    /// Variable-order (1–5) BDF with its predictor–corrector error estimate.
    Bdf,
    /// TR-BDF2 (SDIRK, order 2, L-stable, embedded order-3 estimate).
    TrBdf2,
    /// ESDIRK34 (order 3, four stages, embedded estimate). The scene's `"sdirk"`.
    Esdirk34,
}

impl OdeMethod {
    pub fn name(&self) -> &'static str {
        match self {
            OdeMethod::Bdf => "bdf",
            OdeMethod::TrBdf2 => "sdirk_tr_bdf2",
            OdeMethod::Esdirk34 => "sdirk",
        }
    }
    /// Classical order of the method (BDF: its maximum order).
    pub fn order(&self) -> usize {
        match self {
            OdeMethod::Bdf => 5,
            OdeMethod::TrBdf2 => 2,
            OdeMethod::Esdirk34 => 3,
        }
    }
}

/// Tolerances handed to diffsol: relative, and absolute per block (u, v).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OdeTolerances {
    pub rtol: f64,
    pub atol_u: f64,
    pub atol_v: f64,
}

impl OdeTolerances {
    /// The scene mapping documented in the module docs.
    pub fn from_scene(error_tol: f64, ro: f64, omega: f64, t_end: f64) -> Self {
        let atol_u = error_tol * 1e-2 * ro;
        let omega_ref = if omega.abs() > 0.0 {
            omega.abs()
        } else {
            2.0 * PI / t_end.max(f64::MIN_POSITIVE)
        };
        Self {
            rtol: error_tol,
            atol_u,
            atol_v: atol_u * omega_ref,
        }
    }
}

/// The first-order system B ẏ = F(y, t) over the free dofs of a [`Transient`].
pub struct FirstOrder<'t> {
    tr: RefCell<&'t mut Transient>,
    /// Number of free displacement dofs (y has 2n entries).
    n: usize,
    /// Full dof index of each equation.
    free: Vec<usize>,
    /// Free-dof CSC pattern (the assembler's).
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// M_ff values in that pattern.
    m_ff: Vec<f64>,
    jac_sparsity: SymbolicSparseColMat<usize>,
    mass_sparsity: SymbolicSparseColMat<usize>,
    y0: Vec<f64>,
    ctx: FaerContext,
    /// Right-hand side and Jacobian evaluations (count).
    evals: RefCell<(usize, usize)>,
}

fn col(v: &V) -> &[f64] {
    v.inner().col_as_slice(0)
}

impl<'t> FirstOrder<'t> {
    /// Build the system from the transient model at its current state (t, u_n, v_n).
    pub fn new(tr: &'t mut Transient) -> Result<Self, SolveError> {
        let dofs = &tr.sys.dofs;
        if dofs.per_cell > 0 || dofs.n_global > 0 || dofs.field.iter().any(|&f| f != 0) {
            return Err(SolveError::Integrator {
                t: tr.state.t,
                message: "BDF/SDIRK on y = (u, v) need a pure displacement model: cell pressures \
                          (material.formulation exact) or the load-controlled road height \
                          (road.load) make the system differential-algebraic; use \
                          time.integrator = \"generalized_alpha\""
                    .into(),
            });
        }
        let n = dofs.n_eq;
        let mut free = vec![0; n];
        for (d, &e) in dofs.eq.iter().enumerate() {
            if e < CONSTRAINED {
                free[e as usize] = d;
            }
        }
        let (col_ptr, row_idx) = (tr.sys.asm.col_ptr.clone(), tr.sys.asm.row_idx.clone());
        let nnz = row_idx.len();
        // M_ff in the assembler's pattern.
        let mut m_ff = vec![0.0; nnz];
        for c in 0..tr.sys.model.mesh.n_cells() {
            let cd = dofs.cell(c);
            let m = &tr.mass[tr.mass_off[c]..tr.mass_off[c + 1]];
            let nn = tr.sys.model.mesh.cell_nodes(c).len();
            for a in 0..nn {
                for b in 0..nn {
                    let mab = m[a * nn + b];
                    if mab == 0.0 {
                        continue;
                    }
                    for i in 0..2 {
                        let (er, ec) = (
                            dofs.eq[cd[2 * a + i] as usize],
                            dofs.eq[cd[2 * b + i] as usize],
                        );
                        if er >= CONSTRAINED || ec >= CONSTRAINED {
                            continue;
                        }
                        let (s, e) = (col_ptr[ec as usize], col_ptr[ec as usize + 1]);
                        if let Ok(p) = row_idx[s..e].binary_search(&(er as usize)) {
                            m_ff[s + p] += mab;
                        }
                    }
                }
            }
        }
        // Jacobian pattern (2n × 2n): u-column j: rows n + K's; v-column j: row j, then n + K's.
        let mut jcp = Vec::with_capacity(2 * n + 1);
        let mut jri = Vec::with_capacity(2 * nnz + n);
        jcp.push(0);
        for j in 0..n {
            jri.extend(row_idx[col_ptr[j]..col_ptr[j + 1]].iter().map(|r| n + r));
            jcp.push(jri.len());
        }
        for j in 0..n {
            jri.push(j);
            jri.extend(row_idx[col_ptr[j]..col_ptr[j + 1]].iter().map(|r| n + r));
            jcp.push(jri.len());
        }
        // Mass pattern: identity, then M_ff's (the assembler's) pattern.
        let mut mcp = Vec::with_capacity(2 * n + 1);
        let mut mri = Vec::with_capacity(nnz + n);
        mcp.push(0);
        for j in 0..n {
            mri.push(j);
            mcp.push(mri.len());
        }
        for j in 0..n {
            mri.extend(row_idx[col_ptr[j]..col_ptr[j + 1]].iter().map(|r| n + r));
            mcp.push(mri.len());
        }
        let jac_sparsity = SymbolicSparseColMat::new_checked(2 * n, 2 * n, jcp, None, jri);
        let mass_sparsity = SymbolicSparseColMat::new_checked(2 * n, 2 * n, mcp, None, mri);
        let mut y0 = vec![0.0; 2 * n];
        for (e, &d) in free.iter().enumerate() {
            y0[e] = tr.state.u[d];
            y0[n + e] = tr.state.v[d];
        }
        Ok(Self {
            tr: RefCell::new(tr),
            n,
            free,
            col_ptr,
            row_idx,
            m_ff,
            jac_sparsity,
            mass_sparsity,
            y0,
            ctx: FaerContext::default(),
            evals: RefCell::new((0, 0)),
        })
    }

    /// Number of states (2 × free dofs).
    pub fn n_states(&self) -> usize {
        2 * self.n
    }
    /// Initial state y0 = (u, v) of the free dofs.
    pub fn initial_state(&self) -> &[f64] {
        &self.y0
    }
    /// (right-hand side, Jacobian) evaluations so far.
    pub fn evaluations(&self) -> (usize, usize) {
        *self.evals.borrow()
    }

    /// Put (u, v) of the free dofs at time t into the transient model's assembly state: hub
    /// positions and road from the kinematics, hub velocity and acceleration exact; the
    /// quadrature-point history (viscoelastic materials) is evaluated over the step from the
    /// last accepted time to t (the caller resets [`crate::physics::SolidModel::history_dt`]).
    fn load_state(&self, tr: &mut Transient, t: f64, y: &[f64]) {
        let n = self.n;
        tr.sys.model.history_dt = (t - tr.state.t).max(0.0);
        tr.prescribe(t);
        tr.hub_rates(t);
        for (e, &d) in self.free.iter().enumerate() {
            tr.sys.x[d] = y[e];
        }
        tr.xa.copy_from_slice(&tr.sys.x);
        tr.va.copy_from_slice(&tr.next.v);
        tr.aa.copy_from_slice(&tr.next.a);
        for (e, &d) in self.free.iter().enumerate() {
            tr.va[d] = y[n + e];
            tr.aa[d] = 0.0;
        }
    }

    /// F(y, t) = (v, −R) into `out`. Returns false if the state is inadmissible (J ≤ 0 or a
    /// non-finite force): `out` is then filled with NaN, which makes diffsol reject the step.
    pub fn eval_rhs(&self, t: f64, y: &[f64], out: &mut [f64]) -> bool {
        self.evals.borrow_mut().0 += 1;
        let n = self.n;
        let mut tr = self.tr.borrow_mut();
        self.load_state(&mut tr, t, y);
        let ok = tr.assemble_dynamic(false, 1.0, 0.0, 0.0, 0.0);
        tr.sys.model.history_dt = 0.0;
        if !ok {
            out.iter_mut().for_each(|v| *v = f64::NAN);
            return false;
        }
        out[..n].copy_from_slice(&y[n..]);
        for (o, r) in out[n..].iter_mut().zip(&tr.sys.asm.residual) {
            *o = -r;
        }
        true
    }

    /// K = ∂R/∂u and C = ∂R/∂v in the assembler's pattern.
    fn tangents(&self, t: f64, y: &[f64]) -> (Vec<f64>, Vec<f64>) {
        self.evals.borrow_mut().1 += 1;
        let mut tr = self.tr.borrow_mut();
        self.load_state(&mut tr, t, y);
        tr.assemble_dynamic(true, 1.0, 0.0, 0.0, 0.0);
        let k = tr.sys.asm.values.clone();
        tr.assemble_dynamic(true, 1.0, 1.0, 0.0, 0.0);
        tr.sys.model.history_dt = 0.0;
        let c: Vec<f64> = tr
            .sys
            .asm
            .values
            .iter()
            .zip(&k)
            .map(|(a, b)| a - b)
            .collect();
        (k, c)
    }

    /// Values of ∂F/∂y in the Jacobian pattern ([`Self::jacobian_pattern`]).
    pub fn eval_jacobian(&self, t: f64, y: &[f64], vals: &mut [f64]) {
        let (k, c) = self.tangents(t, y);
        let nnz = k.len();
        for (v, kk) in vals[..nnz].iter_mut().zip(&k) {
            *v = -kk;
        }
        for j in 0..self.n {
            let (s, e) = (self.col_ptr[j], self.col_ptr[j + 1]);
            let base = nnz + j + s;
            vals[base] = 1.0;
            for p in s..e {
                vals[base + 1 + (p - s)] = -c[p];
            }
        }
    }

    /// CSC pattern (column pointers, row indices) of ∂F/∂y.
    pub fn jacobian_pattern(&self) -> (&[usize], &[usize]) {
        (self.jac_sparsity.col_ptr(), self.jac_sparsity.row_idx())
    }

    /// Values of B in its pattern ([`Self::mass_pattern`]).
    pub fn mass_values(&self) -> Vec<f64> {
        let mut v = vec![1.0; self.n];
        v.extend_from_slice(&self.m_ff);
        v
    }
    pub fn mass_pattern(&self) -> (&[usize], &[usize]) {
        (self.mass_sparsity.col_ptr(), self.mass_sparsity.row_idx())
    }

    /// y = M_ff x (assembler pattern).
    fn m_ff_mul(&self, x: &[f64], y: &mut [f64]) {
        y.iter_mut().for_each(|v| *v = 0.0);
        for (j, &xj) in x.iter().enumerate().take(self.n) {
            let col = self.col_ptr[j]..self.col_ptr[j + 1];
            for (&i, &m) in self.row_idx[col.clone()].iter().zip(&self.m_ff[col]) {
                y[i] += m * xj;
            }
        }
    }

    /// ẏ at (y, t): (v, M_ff⁻¹ (−R)) by Jacobi-preconditioned CG on the (SPD) mass matrix.
    pub fn consistent_rate(&self, t: f64, y: &[f64]) -> Option<Vec<f64>> {
        let n = self.n;
        let mut f = vec![0.0; 2 * n];
        if !self.eval_rhs(t, y, &mut f) {
            return None;
        }
        let b = f[n..].to_vec();
        let mut diag = vec![0.0; n];
        for (j, d) in diag.iter_mut().enumerate() {
            for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                if self.row_idx[p] == j {
                    *d = self.m_ff[p];
                }
            }
        }
        if diag.iter().any(|d| *d <= 0.0) {
            return None;
        }
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let mut x = vec![0.0; n];
        let mut r = b.clone();
        let mut z: Vec<f64> = r.iter().zip(&diag).map(|(r, d)| r / d).collect();
        let mut p = z.clone();
        let mut q = vec![0.0; n];
        let bn = dot(&b, &b).sqrt();
        let mut rz = dot(&r, &z);
        for _ in 0..10 * n.max(10) {
            if dot(&r, &r).sqrt() <= 1e-14 * bn || bn == 0.0 {
                break;
            }
            self.m_ff_mul(&p, &mut q);
            let alpha = rz / dot(&p, &q);
            for i in 0..n {
                x[i] += alpha * p[i];
                r[i] -= alpha * q[i];
            }
            for i in 0..n {
                z[i] = r[i] / diag[i];
            }
            let rz1 = dot(&r, &z);
            let beta = rz1 / rz;
            rz = rz1;
            for i in 0..n {
                p[i] = z[i] + beta * p[i];
            }
        }
        f[n..].copy_from_slice(&x);
        Some(f)
    }

    /// Fill the driver's state (t, full u_n, v_n, a_n, and the assembly state) from (y, ẏ).
    fn commit(&self, t: f64, y: &[f64], dy: &[f64]) {
        let n = self.n;
        let mut tr = self.tr.borrow_mut();
        tr.prescribe(t);
        tr.hub_rates(t);
        for (e, &d) in self.free.iter().enumerate() {
            tr.sys.x[d] = y[e];
            tr.next.v[d] = y[n + e];
            tr.next.a[d] = dy[n + e];
        }
        // The history advances over the accepted step (its forces were evaluated over it).
        let dt = (t - tr.state.t).max(0.0);
        tr.commit_state(t, Some(dt));
    }
}

impl Op for FirstOrder<'_> {
    type T = f64;
    type V = V;
    type M = M;
    type C = FaerContext;
    fn nstates(&self) -> usize {
        2 * self.n
    }
    fn nout(&self) -> usize {
        2 * self.n
    }
    fn nparams(&self) -> usize {
        0
    }
    fn context(&self) -> &FaerContext {
        &self.ctx
    }
}

/// The right-hand side F (and its Jacobian) as a diffsol operator.
pub struct Rhs<'a, 't>(&'a FirstOrder<'t>);
/// The mass B as a diffsol operator.
pub struct Mass<'a, 't>(&'a FirstOrder<'t>);
/// The initial state as a diffsol operator.
pub struct Init<'a, 't>(&'a FirstOrder<'t>);

macro_rules! delegate_op {
    ($ty:ident) => {
        impl Op for $ty<'_, '_> {
            type T = f64;
            type V = V;
            type M = M;
            type C = FaerContext;
            fn nstates(&self) -> usize {
                2 * self.0.n
            }
            fn nout(&self) -> usize {
                2 * self.0.n
            }
            fn nparams(&self) -> usize {
                0
            }
            fn context(&self) -> &FaerContext {
                &self.0.ctx
            }
        }
    };
}
delegate_op!(Rhs);
delegate_op!(Mass);
delegate_op!(Init);

impl NonLinearOp for Rhs<'_, '_> {
    fn call_inplace(&self, x: &V, t: f64, y: &mut V) {
        y.for_each_batch_host([x], |y, [x], _| {
            self.0.eval_rhs(t, x, y);
        });
    }
}

impl NonLinearOpJacobian for Rhs<'_, '_> {
    fn jac_mul_inplace(&self, x: &V, t: f64, v: &V, y: &mut V) {
        let n = self.0.n;
        let (k, c) = self.0.tangents(t, col(x));
        let v = col(v);
        y.for_each_batch_host([], |y, [], _| {
            y.iter_mut().for_each(|a| *a = 0.0);
            for j in 0..n {
                y[j] = v[n + j];
                for p in self.0.col_ptr[j]..self.0.col_ptr[j + 1] {
                    let r = n + self.0.row_idx[p];
                    y[r] -= k[p] * v[j] + c[p] * v[n + j];
                }
            }
        });
    }
    fn jacobian_inplace(&self, x: &V, t: f64, y: &mut M) {
        let data = &mut y.inner_mut()[0];
        if data.row_idx().len() == self.0.jac_sparsity.row_idx().len() {
            self.0.eval_jacobian(t, col(x), data.val_mut());
        } else {
            // Not our pattern (should not happen): fall back to diffsol's column-by-column build.
            self._default_jacobian_inplace(x, t, y);
        }
    }
    fn jacobian_sparsity(&self) -> Option<SymbolicSparseColMat<usize>> {
        Some(self.0.jac_sparsity.clone())
    }
}

impl LinearOp for Mass<'_, '_> {
    fn gemv_inplace(&self, x: &V, _t: f64, beta: f64, y: &mut V) {
        let n = self.0.n;
        let mut mv = vec![0.0; n];
        self.0.m_ff_mul(&col(x)[n..], &mut mv);
        let xs = col(x);
        y.for_each_batch_host([], |y, [], _| {
            for j in 0..n {
                y[j] = xs[j] + beta * y[j];
                y[n + j] = mv[j] + beta * y[n + j];
            }
        });
    }
    fn matrix_inplace(&self, t: f64, y: &mut M) {
        let data = &mut y.inner_mut()[0];
        if data.row_idx().len() == self.0.mass_sparsity.row_idx().len() {
            data.val_mut().copy_from_slice(&self.0.mass_values());
        } else {
            self._default_matrix_inplace(t, y);
        }
    }
    fn sparsity(&self) -> Option<SymbolicSparseColMat<usize>> {
        Some(self.0.mass_sparsity.clone())
    }
}

impl ConstantOp for Init<'_, '_> {
    fn call_inplace(&self, _t: f64, y: &mut V) {
        y.for_each_batch_host([], |y, [], _| y.copy_from_slice(&self.0.y0));
    }
}

type Unit<'a> = ParameterisedOp<'a, UnitCallable<M>>;

impl<'a, 't> OdeEquationsRef<'a> for FirstOrder<'t> {
    type Rhs = Rhs<'a, 't>;
    type Mass = Mass<'a, 't>;
    type Root = Unit<'a>;
    type Init = Init<'a, 't>;
    type Out = Unit<'a>;
    type Reset = Unit<'a>;
}

impl<'t> OdeEquations for FirstOrder<'t> {
    fn rhs(&self) -> Rhs<'_, 't> {
        Rhs(self)
    }
    fn mass(&self) -> Option<Mass<'_, 't>> {
        Some(Mass(self))
    }
    fn init(&self) -> Init<'_, 't> {
        Init(self)
    }
    fn set_params(&mut self, _p: &V) {}
    fn get_params(&self, _p: &mut V) {}
}

/// Flush-to-zero and denormals-are-zero on this thread while alive (x86-64 MXCSR bits 15
/// and 6); the previous mode is restored on drop.
struct FlushToZero {
    #[cfg(target_arch = "x86_64")]
    saved: u32,
}

impl FlushToZero {
    #[allow(deprecated)]
    fn new() -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: reading and writing MXCSR only changes this thread's float modes.
            let saved = unsafe { std::arch::x86_64::_mm_getcsr() };
            unsafe { std::arch::x86_64::_mm_setcsr(saved | 0x8040) };
            Self { saved }
        }
        #[cfg(not(target_arch = "x86_64"))]
        Self {}
    }
}

impl Drop for FlushToZero {
    #[allow(deprecated)]
    fn drop(&mut self) {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: restores the mode saved in `new`.
        unsafe {
            std::arch::x86_64::_mm_setcsr(self.saved)
        };
    }
}

fn panic_message(payload: Box<dyn std::any::Any + Send>) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic".to_string()
    }
}

/// Integrate the transient model with diffsol's `method` until steady (or t_end), with the same
/// report, steady-state monitor and per-step callback as [`super::integrate`]. Uses from `opts`:
/// dt (first step), dt_min, t_end, steady_tol, stop_at_steady, max_steps, land_on_passages.
// The failed run's report rides with its error, once per run: boxing it would buy nothing.
#[allow(clippy::result_large_err)]
pub fn integrate_first_order(
    tr: &mut Transient,
    method: OdeMethod,
    opts: &TimeOptions,
    tol: OdeTolerances,
    mut on_step: impl FnMut(&Transient, &TransientReport),
) -> Result<TransientReport, (SolveError, TransientReport)> {
    let _ftz = FlushToZero::new();
    let mut rep = TransientReport {
        dt_min_used: f64::INFINITY,
        ..Default::default()
    };
    let fail = |t: f64, message: String| SolveError::Integrator { t, message };
    let mut monitor = SteadyMonitor::new(&tr.sys);
    tr.sys.x.copy_from_slice(&tr.state.u);
    tr.prescribe(tr.state.t);
    let snap0 = tr.snapshot();
    rep.history.push(snap0);
    let t0 = tr.state.t;
    let dtheta = monitor.as_ref().map(|m| m.dtheta);
    let kin = tr.kin.clone();
    let fo = match FirstOrder::new(tr) {
        Ok(f) => f,
        Err(e) => return Err((e, rep)),
    };
    let n = fo.n;
    let Some(dy0) = fo.consistent_rate(t0, &fo.y0) else {
        return Err((SolveError::InadmissibleStart, rep));
    };
    let atol: Vec<f64> = (0..2 * n)
        .map(|i| if i < n { tol.atol_u } else { tol.atol_v })
        .collect();
    let mut problem: OdeSolverProblem<FirstOrder<'_>> = match OdeBuilder::<M>::new()
        .t0(t0)
        .h0(opts.dt)
        .rtol(tol.rtol)
        .atol(atol)
        .build_from_eqn(fo)
    {
        Ok(p) => p,
        Err(e) => return Err((fail(t0, e.to_string()), rep)),
    };
    problem.ode_options.min_timestep = opts.dt_min;
    problem.ode_options.max_nonlinear_solver_iterations = 10;
    let res = catch_unwind(AssertUnwindSafe(|| match method {
        OdeMethod::Bdf => {
            let mut state = problem.bdf_state::<LS>()?;
            fix_state(&mut state, &dy0, opts.dt);
            let solver = problem.bdf_solver::<LS>(state)?;
            Ok::<_, diffsol::DiffsolError>(Solver::Bdf(Box::new(solver)))
        }
        OdeMethod::TrBdf2 | OdeMethod::Esdirk34 => {
            let tableau = if method == OdeMethod::TrBdf2 {
                diffsol::Tableau::<f64>::tr_bdf2()
            } else {
                diffsol::Tableau::<f64>::esdirk34()
            };
            let mut state = problem.rk_state(&tableau)?;
            fix_state(&mut state, &dy0, opts.dt);
            let solver = problem.sdirk_solver::<LS, _>(state, tableau)?;
            Ok(Solver::Sdirk(Box::new(solver)))
        }
    }));
    let mut solver = match res {
        Ok(Ok(s)) => s,
        Ok(Err(e)) => return Err((fail(t0, e.to_string()), rep)),
        Err(p) => {
            return Err((
                fail(t0, format!("diffsol panicked: {}", panic_message(p))),
                rep,
            ))
        }
    };
    let fo = &problem.eqn;

    // Stop times: t_end, and every node passage once the ramps are done.
    let ramps_done = kin.ramps_done();
    let next_passage = |t: f64| -> Option<f64> {
        let dth = dtheta?;
        if !opts.land_on_passages || kin.omega.target <= 0.0 {
            return None;
        }
        let ts = t.max(ramps_done);
        let k = (kin.phi(ts) / dth + 1e-9).floor() + 1.0;
        let target = k * dth;
        let mut hi = ts + dth / kin.omega.target;
        while kin.phi(hi) < target {
            hi += dth / kin.omega.target;
        }
        let mut lo = ts;
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if kin.phi(mid) < target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(hi)
    };
    let stop_after = |t: f64| -> f64 { next_passage(t).map_or(opts.t_end, |p| p.min(opts.t_end)) };
    let mut t_stop = stop_after(t0);
    if let Err(e) = solver.set_stop_time(t_stop) {
        return Err((fail(t0, e.to_string()), rep));
    }
    let (mut y_prev, mut dy_prev) = (fo.y0.clone(), dy0.clone());
    let (mut u0, mut v0) = {
        let tr = fo.tr.borrow();
        (tr.state.u.clone(), tr.state.v.clone())
    };
    let mut snap0 = snap0;
    let mut t_prev = t0;
    let result: Result<(), SolveError> = loop {
        if crate::io::record::interrupted() {
            break Err(SolveError::Interrupted { at: t_prev });
        }
        if rep.steps >= opts.max_steps {
            break Ok(());
        }
        let step = catch_unwind(AssertUnwindSafe(|| solver.step()));
        let reason = match step {
            Ok(Ok(r)) => r,
            Ok(Err(e)) => break Err(fail(t_prev, e.to_string())),
            Err(p) => {
                break Err(fail(
                    t_prev,
                    format!("diffsol panicked: {}", panic_message(p)),
                ))
            }
        };
        let (t, y, dy) = solver.state_vectors();
        if !y.iter().all(|v| v.is_finite()) {
            break Err(fail(t, "non-finite state".into()));
        }
        let t = if reason == OdeSolverStopReason::TstopReached {
            t_stop
        } else {
            t
        };
        solver.bump_newton_fail_limit();
        fo.commit(t, &y, &dy);
        y_prev.copy_from_slice(&y);
        dy_prev.copy_from_slice(&dy);
        let h = t - t_prev;
        rep.steps += 1;
        let st = solver.stats();
        rep.newton_iterations = st.0;
        rep.rejected = st.1;
        rep.dt_min_used = rep.dt_min_used.min(h);
        rep.dt_max_used = rep.dt_max_used.max(h);
        {
            let tr = fo.tr.borrow();
            let snap1 = tr.snapshot_light();
            if let Some(m) = &mut monitor {
                if tr.state.t >= ramps_done
                    && m.check(
                        &tr,
                        t_prev,
                        &u0,
                        &v0,
                        &snap0,
                        &snap1,
                        opts.steady_tol,
                        &|t| tr.kin.phi(t),
                    )
                    && !rep.steady
                {
                    rep.steady = true;
                    rep.time_to_steady = Some(tr.state.t);
                }
                rep.passages = m.passages;
                rep.last_change = [
                    m.last_change.0,
                    m.last_change.1,
                    m.last_change.2,
                    m.last_change.3,
                ];
            }
            snap0 = snap1;
            rep.final_time = tr.state.t;
            rep.revolutions = tr.kin.phi(tr.state.t) / (2.0 * PI);
            on_step(&tr, &rep);
            u0.copy_from_slice(&tr.state.u);
            v0.copy_from_slice(&tr.state.v);
        }
        t_prev = t;
        if rep.steady && opts.stop_at_steady {
            break Ok(());
        }
        if t >= opts.t_end - 1e-12 * opts.t_end.abs() {
            break Ok(());
        }
        if reason == OdeSolverStopReason::TstopReached {
            t_stop = stop_after(t);
            if let Err(e) = solver.set_stop_time(t_stop) {
                break Err(fail(t, e.to_string()));
            }
        }
    };
    // The driver's state is the last accepted step (rhs evaluations of a failed step used the
    // assembly buffers as scratch).
    fo.commit(t_prev, &y_prev, &dy_prev);
    let mut tr = fo.tr.borrow_mut();
    if let Some(m) = &monitor {
        rep.passages = m.passages;
        if m.passages > 0 {
            tr.steady_field = Some(m.field.clone());
        }
        rep.passage_log = m.log.clone();
        rep.passage_mean = m.passage_mean;
    }
    rep.history.push(tr.snapshot());
    if rep.dt_min_used == f64::INFINITY {
        rep.dt_min_used = 0.0;
    }
    match result {
        Ok(()) => Ok(rep),
        Err(e) => Err((e, rep)),
    }
}

/// Set diffsol's initial state derivative to B⁻¹F (diffsol takes ẏ0 = F(y0), which is wrong with
/// a non-identity mass) and the first step to `h`.
fn fix_state<S: diffsol::OdeSolverState<V>>(state: &mut S, dy0: &[f64], h: f64) {
    let s = state.as_mut();
    s.dy.for_each_batch_host([], |y, [], _| y.copy_from_slice(dy0));
    *s.h = h;
}

type BdfSolver<'p, 't> = diffsol::Bdf<'p, FirstOrder<'t>, LS>;
type SdirkSolver<'p, 't> = diffsol::Sdirk<'p, FirstOrder<'t>, LS>;

/// The two diffsol solver types behind one small interface.
enum Solver<'p, 't> {
    Bdf(Box<BdfSolver<'p, 't>>),
    Sdirk(Box<SdirkSolver<'p, 't>>),
}

impl Solver<'_, '_> {
    fn step(&mut self) -> Result<OdeSolverStopReason<f64>, diffsol::DiffsolError> {
        match self {
            Solver::Bdf(s) => s.step(),
            Solver::Sdirk(s) => s.step(),
        }
    }
    fn set_stop_time(&mut self, t: f64) -> Result<(), diffsol::DiffsolError> {
        match self {
            Solver::Bdf(s) => s.set_stop_time(t),
            Solver::Sdirk(s) => s.set_stop_time(t),
        }
    }
    fn state_vectors(&self) -> (f64, Vec<f64>, Vec<f64>) {
        let st = match self {
            Solver::Bdf(s) => s.state(),
            Solver::Sdirk(s) => s.state(),
        };
        (st.t, st.y.clone_as_vec(), st.dy.clone_as_vec())
    }
    /// (Newton iterations, rejected steps: error-test plus Newton failures).
    fn stats(&self) -> (usize, usize) {
        let s = match self {
            Solver::Bdf(s) => s.get_statistics(),
            Solver::Sdirk(s) => s.get_statistics(),
        };
        (
            s.number_of_nonlinear_solver_iterations,
            s.number_of_error_test_failures + s.number_of_nonlinear_solver_fails,
        )
    }
    /// diffsol 0.18 compares its *cumulative* count of Newton failures with
    /// `maximum_newton_fails` (see [`crate::contact::stick_slip`]): move the limit along so that
    /// it acts per step.
    fn bump_newton_fail_limit(&mut self) {
        const PER_STEP: usize = 20;
        match self {
            Solver::Bdf(s) => {
                let f = s.get_statistics().number_of_nonlinear_solver_fails;
                s.config_mut().maximum_newton_fails = f + PER_STEP;
            }
            Solver::Sdirk(s) => {
                let f = s.get_statistics().number_of_nonlinear_solver_fails;
                s.config_mut().maximum_newton_fails = f + PER_STEP;
            }
        }
    }
}
