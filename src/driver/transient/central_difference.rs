//! Explicit central difference with the lumped (HRZ) mass: a_n = −M_L⁻¹ f(u_n, v_{n−1/2}),
//! v_{n+1/2} = v_{n−1/2} + Δt a_n, u_{n+1} = u_n + Δt v_{n+1/2}. The step is bounded by a
//! stable-step estimate ([`Transient::stable_step`]).

use super::integrator::IntegratorSpec;
use super::{Body, Scheme, StepMethod, Transient};
use crate::assembly::CONSTRAINED;
use crate::solver::{Newton, SolveError};

/// The scene's `"central_difference"`: the one-step loop of [`super::integrate`], lumped mass.
pub struct CentralDifference;

impl IntegratorSpec for CentralDifference {
    fn scheme_3d(_rho_inf: f64) -> Option<Scheme<crate::model::Solid3DSystem>> {
        Some(Scheme::central_difference())
    }

    fn scheme(_rho_inf: f64) -> Scheme {
        Scheme::central_difference()
    }
}

/// The explicit central-difference step: no Newton system, no error estimate.
#[derive(Clone, Copy, Debug)]
pub struct CentralDifferenceStep;

impl<B: Body> StepMethod<B> for CentralDifferenceStep {
    fn name(&self) -> &'static str {
        "central_difference"
    }

    fn attempt(
        &self,
        tr: &mut Transient<B>,
        _newton: &mut Newton,
        dt: f64,
    ) -> Result<(f64, usize), SolveError> {
        tr.attempt_central_difference(dt)
    }

    fn evaluate(&self, _tr: &mut Transient<B>, _with_matrix: bool) -> bool {
        false
    }

    fn estimates_error(&self) -> bool {
        false
    }

    fn explicit(&self) -> bool {
        true
    }
}

impl<B: Body> Transient<B> {
    /// One central-difference step of size `dt` from the committed state (left pending).
    pub(super) fn attempt_central_difference(
        &mut self,
        dt: f64,
    ) -> Result<(f64, usize), SolveError> {
        let t1 = self.state.t + dt;
        // v_n ≈ v_{n−1/2} for the contact rates; a_n = −M_L⁻¹ f(u_n).
        self.sys.x_mut().copy_from_slice(&self.state.u);
        self.prescribe(self.state.t);
        self.xa.copy_from_slice(self.sys.x());
        self.va.copy_from_slice(&self.state.v);
        self.aa.iter_mut().for_each(|v| *v = 0.0);
        self.t_eval = self.state.t;
        if !self.assemble_dynamic(false, 1.0, 0.0, 0.0, 0.0) {
            // From an admissible committed state, only an unstable step gets here.
            return Err(SolveError::ExplicitUnstable {
                t: self.state.t,
                dt,
                dt_stable: self.dt_stable,
            });
        }
        // a_n = −M_L⁻¹ f(u_n) on the free dofs (into next.a; the committed a_n stays
        // until the step is accepted), then v_{n+1/2} = v_{n−1/2} + Δt a_n and
        // u_{n+1} = u_n + Δt v_{n+1/2}.
        self.next.a.copy_from_slice(&self.state.a);
        for d in 0..self.state.u.len() {
            let e = self.sys.dof_map().eq[d];
            if e < CONSTRAINED && self.ml[d] > 0.0 {
                self.next.a[d] = -self.sys.assembler().residual[e as usize] / self.ml[d];
            }
        }
        // Prescribed dofs: velocity from the prescribed positions.
        self.prescribe(t1);
        self.next.v.copy_from_slice(&self.state.v);
        for d in 0..self.state.u.len() {
            if self.sys.dof_map().eq[d] < CONSTRAINED && self.ml[d] > 0.0 {
                self.next.v[d] += dt * self.next.a[d];
                self.sys.x_mut()[d] = self.state.u[d] + dt * self.next.v[d];
            } else {
                self.next.v[d] = (self.sys.x()[d] - self.state.u[d]) / dt;
            }
        }
        self.pending = Some((t1, dt));
        Ok((0.0, 0))
    }

    /// Stable time step of the central-difference scheme with its lagged-velocity damping:
    /// Δt = (2/ω_max)(√(1 + ξ²) − ξ) (Belytschko), ω_max² the largest eigenvalue of
    /// M_L⁻¹ (K + K_c) by power iteration on the tangent at the current state plus the contact
    /// penalty K_c = ∂t_n/∂δ · diag(Σ_b |∫ N_a N_b ds0|) on the x2 dofs of the whole contact
    /// boundary (every facet may come into contact while rolling; evaluated at the final
    /// penetration `delta_ref`), and ξ = vᵀ C v / (2 ω_max vᵀ M_L v) on the dominant mode v, with C
    /// the strain-rate damping matrix (K assembled with ∂v/∂u = 1 minus K) plus the contact
    /// normal damping ∂t_n/∂δ̇ on the same boundary diagonal. 5 % margin on ω_max (power
    /// iteration approaches λ_max from below).
    pub fn stable_step(&mut self, delta_ref: f64) -> f64 {
        self.sys.x_mut().copy_from_slice(&self.state.u);
        self.xa.copy_from_slice(&self.state.u);
        self.va.copy_from_slice(&self.state.v);
        self.aa.iter_mut().for_each(|v| *v = 0.0);
        self.t_eval = self.state.t;
        if !self.assemble_dynamic(true, 1.0, 0.0, 0.0, 0.0) {
            return f64::NAN;
        }
        let k = self.sys.assembler().values.clone();
        let n = self.sys.dof_map().n_eq;
        let mut cmat = Vec::new();
        if self.sys.has_rate_damping() {
            if !self.assemble_dynamic(true, 1.0, 1.0, 0.0, 0.0) {
                return f64::NAN;
            }
            cmat = self
                .sys
                .assembler()
                .values
                .iter()
                .zip(&k)
                .map(|(a, b)| a - b)
                .collect();
        }
        // Boundary diagonals of the contact penalty and damping (equation numbering).
        let (kc, cc) = self
            .sys
            .contact_diagonals(delta_ref)
            .unwrap_or_else(|| (vec![0.0; n], vec![0.0; n]));
        let mut ml = vec![0.0; n];
        let dofs = self.sys.dof_map();
        for (d, &e) in dofs.eq.iter().enumerate() {
            if e < CONSTRAINED && d < dofs.n_u {
                ml[e as usize] = self.ml[d];
            }
        }
        let minv: Vec<f64> = ml
            .iter()
            .map(|&m| if m > 0.0 { 1.0 / m } else { 0.0 })
            .collect();
        let mut x: Vec<f64> = (0..n)
            .map(|i| 1.0 + 0.1 * ((i as f64) * 0.37).sin())
            .collect();
        let mut y = vec![0.0; n];
        let mut lam = 0.0;
        self.sys.assembler_mut().values.copy_from_slice(&k);
        for _ in 0..80 {
            self.sys.assembler().matvec(&x, &mut y);
            for i in 0..n {
                y[i] = (y[i] + kc[i] * x[i]) * minv[i];
            }
            let ny = y.iter().map(|v| v * v).sum::<f64>().sqrt();
            let nx = x.iter().map(|v| v * v).sum::<f64>().sqrt();
            lam = ny / nx.max(f64::MIN_POSITIVE);
            for i in 0..n {
                x[i] = y[i] / ny.max(f64::MIN_POSITIVE);
            }
        }
        let omega = (1.05 * lam).sqrt();
        // Damping ratio of the dominant mode.
        let mut xcx: f64 = (0..n).map(|i| cc[i] * x[i] * x[i]).sum();
        if !cmat.is_empty() {
            self.sys.assembler_mut().values.copy_from_slice(&cmat);
            self.sys.assembler().matvec(&x, &mut y);
            xcx += x.iter().zip(&y).map(|(a, b)| a * b).sum::<f64>();
            self.sys.assembler_mut().values.copy_from_slice(&k);
        }
        let xmx: f64 = (0..n).map(|i| ml[i] * x[i] * x[i]).sum();
        let xi = (xcx / (2.0 * omega * xmx.max(f64::MIN_POSITIVE))).max(0.0);
        let dt = (2.0 / omega) * ((1.0 + xi * xi).sqrt() - xi);
        self.dt_stable = dt;
        dt
    }
}
