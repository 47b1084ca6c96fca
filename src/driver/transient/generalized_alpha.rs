//! Generalized-α (Chung–Hulbert) on the second-order system, in its force-averaged form
//!
//! ```text
//!   M a_{n+1−αm} + (1 − αf) f(u_{n+1}, v_{n+1}) + αf f(u_n, v_n) = 0,
//!   a_{n+1−αm} = (1 − αm) a_{n+1} + αm a_n,
//! ```
//!
//! with the Newmark relations for (u, v, a) at t_{n+1}; ρ∞ = 1 is the trapezoidal (average
//! acceleration) rule. The force-averaged form is objective: every force is evaluated at an
//! actual configuration (the displacement-averaged form evaluates f at (1 − αf) u_{n+1} + αf
//! u_n, a shrunk, strained configuration of a spinning body: spurious strain O((ωΔt)²)). Each
//! step is one Newton solve, with the hub angle as an extra unknown under torque control. The
//! local error estimate e = (β − 1/6) Δt² (a_{n+1} − a_n) (Zienkiewicz–Xie) drives the
//! adaptive step.

use super::integrator::IntegratorSpec;
use super::{Body, GenAlpha, Scheme, StepMethod, Transient};
use crate::solver::{Newton, SolveError};

/// The scene's `"generalized_alpha"`: the one-step loop of [`super::integrate`] with [`GenAlpha`].
pub struct GeneralizedAlpha;

impl IntegratorSpec for GeneralizedAlpha {
    fn scheme_3d(rho_inf: f64) -> Option<Scheme<crate::model::Solid3DSystem>> {
        Some(Scheme::generalized_alpha(GenAlpha::new(rho_inf)))
    }
}

/// The generalized-α step with the parameters it holds (also HHT-α's, [`super::hht_alpha`]).
#[derive(Clone, Copy, Debug)]
pub struct GeneralizedAlphaStep(pub GenAlpha);

impl<B: Body> StepMethod<B> for GeneralizedAlphaStep {
    fn name(&self) -> &'static str {
        "generalized_alpha"
    }

    fn attempt(
        &self,
        tr: &mut Transient<B>,
        newton: &mut Newton,
        dt: f64,
    ) -> Result<(f64, usize), SolveError> {
        tr.attempt_generalized_alpha(self.0, newton, dt)
    }

    fn evaluate(&self, tr: &mut Transient<B>, with_matrix: bool) -> bool {
        tr.assemble_generalized_alpha(&self.0, with_matrix)
    }

    fn committed(&self, tr: &mut Transient<B>) {
        tr.update_fprev();
    }

    fn estimates_error(&self) -> bool {
        true
    }
}

impl<B: Body> Transient<B> {
    /// One generalized-α step of size `dt` from the committed state: constant-acceleration
    /// predictor, Newton on the force-averaged residual, Newmark update; returns the local
    /// error estimate and the Newton iterations, and leaves the step pending.
    pub(super) fn attempt_generalized_alpha(
        &mut self,
        ga: GenAlpha,
        newton: &mut Newton,
        dt: f64,
    ) -> Result<(f64, usize), SolveError> {
        let t1 = self.state.t + dt;
        // Predictor: constant acceleration.
        for d in 0..self.state.u.len() {
            self.sys.x_mut()[d] =
                self.state.u[d] + dt * self.state.v[d] + 0.5 * dt * dt * self.state.a[d];
        }
        self.prescribe(t1);
        // Viscoelastic history: the kernels evaluate the overstress over this step
        // from the committed state; it is committed only once Newton has converged.
        self.sys.set_history_dt(dt);
        let rep = newton.solve(self);
        self.sys.set_history_dt(0.0);
        let rep = rep?;
        self.last_table = rep.table;
        self.newmark(&ga);
        // Local error relative to the deformation: the displacement from the rigidly
        // rotated reference Q(φ_{n+1}) X (the step increment, used before, is dominated
        // by the rigid rotation ωΔt R and made the estimate blind to error_tol). RMS
        // over the nodes, with a floor of 1e-3 of the wall thickness.
        let phi1 = match &self.hub_angle {
            Some(h) => self.sys.x()[h.iphi],
            None => self.kin.phi(t1),
        };
        let (sn, cs) = phi1.sin_cos();
        let mut num = 0.0;
        let mut den = 0.0;
        let (dim, n_nodes) = (B::DIM, self.sys.n_nodes());
        for n in 0..n_nodes {
            let xr = self.sys.reference_node(n);
            let rigid = [
                cs * xr[0] - sn * xr[1] - xr[0],
                sn * xr[0] + cs * xr[1] - xr[1],
                0.0,
            ];
            for (i, r) in rigid.iter().enumerate().take(dim) {
                let d = dim * n + i;
                let e = (ga.beta - 1.0 / 6.0) * dt * dt * (self.next.a[d] - self.state.a[d]);
                num += e * e;
                let ud = self.sys.x()[d] - r;
                den += ud * ud;
            }
        }
        let nd = (dim * n_nodes).max(1) as f64;
        let floor = 1e-3 * self.wall;
        let err = (num / nd).sqrt() / (den / nd).sqrt().max(floor);
        self.pending = Some((t1, dt));
        Ok((err, rep.iterations))
    }

    /// The step's residual (and tangent) at the trial x = u_{n+1}: Newmark rates, then
    /// R = M a_{n+1−αm} + (1 − αf) f(x, v_{n+1}) + αf f_n with ∂v/∂x = γ/(βΔt) and
    /// ∂a/∂x = 1/(βΔt²).
    pub(super) fn assemble_generalized_alpha(&mut self, ga: &GenAlpha, with_matrix: bool) -> bool {
        self.newmark(ga);
        let dt = self.dt;
        self.t_eval = self.state.t + dt;
        let kv = ga.gamma / (ga.beta * dt);
        let cm = (1.0 - ga.am) / (ga.beta * dt * dt);
        self.assemble_dynamic(with_matrix, 1.0 - ga.af, kv, cm, ga.af)
    }

    /// Newmark update of next.v, next.a and the α-point vectors from the trial x = u_{n+1}. The hub
    /// dofs take the exact velocity and acceleration of the prescribed rotation (a Newmark
    /// recursion on a prescribed history rings at the Nyquist frequency when ρ∞ = 1).
    fn newmark(&mut self, ga: &GenAlpha) {
        let dt = self.dt;
        let (b, g) = (ga.beta, ga.gamma);
        for d in 0..self.state.u.len() {
            let a1 = (self.sys.x()[d] - self.state.u[d] - dt * self.state.v[d]) / (b * dt * dt)
                - (0.5 / b - 1.0) * self.state.a[d];
            let v1 = self.state.v[d] + dt * ((1.0 - g) * self.state.a[d] + g * a1);
            self.next.a[d] = a1;
            self.next.v[d] = v1;
        }
        // Load control: the road height is massless (quasi-static): no rate, so that the
        // predictor keeps it where it was.
        if let Some(ih) = self.road_height_dof() {
            self.next.v[ih] = 0.0;
            self.next.a[ih] = 0.0;
        }
        // Under torque control the hub nodes are part of the dynamics (through φ): Newmark
        // rates like every other node, consistent with the tangent.
        if self.hub_angle.is_none() {
            self.hub_rates(self.state.t + dt);
        }
        for d in 0..self.state.u.len() {
            self.xa[d] = self.sys.x()[d];
            self.va[d] = self.next.v[d];
            self.aa[d] = (1.0 - ga.am) * self.next.a[d] + ga.am * self.state.a[d];
        }
    }
}
