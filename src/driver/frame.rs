//! [`SolidFrame`]: what the recorder sees of a [`SolidSystem`] at a step — nodal Cauchy
//! stresses, contact samples, hub loads and energies — computed only when some sink wants the
//! view ([`crate::io::record::Recorder::wants_view`]).
//!
//! * Nodal stress: the Cauchy stress σ = P Fᵀ/J of each cell evaluated at its nodes and averaged
//!   over the cells sharing a node (discontinuous across cells otherwise).
//! * Strain energy ∫ (W(F) − W(I)) dV and kinetic energy ½ ω² ∫ ρ |F t|² dV (t = (−X2, X1): the
//!   velocity of steady spin is v = ω ∂θχ = ω F t), with the 3×3 Gauss rule per cell.
//! * Hub loads: [`SolidSystem::hub_reaction`].
//!
//! Every recorder is also the solvers' [`StepObserver`] of a [`SolidSystem`]: an accepted step
//! goes to [`SolidSystem::record_step`], the Newton table to the recorder's iteration events,
//! and the interrupt flag answers whether to stop.

use super::SolidSystem;
use crate::contact::ContactSample;
use crate::element::QuadRule;
use crate::io::record::{self, Energy, HubLoads, Recorder, StepView};
use crate::material::Hyperelastic;
use crate::math::{Mat2, Vec2};
use crate::solver::{IterationRecord, RejectedStep, StepInfo, StepObserver};

/// Owned data of a view; [`SolidFrame::view`] lends it out with the system's state.
pub struct SolidFrame {
    pub stress: Vec<[f64; 3]>,
    pub contact: Vec<ContactSample>,
    pub hub: HubLoads,
    pub energy: Energy,
}

impl SolidSystem {
    /// Send the accepted step `info` to the recorder, with a view of the state when the
    /// recorder wants one.
    pub fn record_step<R: Recorder + ?Sized>(&self, info: &StepInfo, rec: &mut R) {
        if rec.wants_view(info) {
            let frame = SolidFrame::capture(self);
            rec.step(info, Some(&frame.view(self, &[])));
        } else {
            rec.step(info, None);
        }
    }
}

impl<R: Recorder + ?Sized> StepObserver<SolidSystem> for R {
    fn stop_requested(&self) -> bool {
        record::interrupted()
    }
    fn observe_newton(
        &mut self,
        step: u64,
        time: f64,
        table: &[IterationRecord],
        fields: &'static [&'static str],
    ) {
        record::emit_newton_table(self, step, time, table, fields);
    }
    fn observe_accepted(&mut self, sys: &SolidSystem, info: &StepInfo) {
        sys.record_step(info, self);
    }
    fn observe_rejected(&mut self, step: &RejectedStep) {
        self.step_rejected(step);
    }
}

impl SolidFrame {
    pub fn capture(sys: &SolidSystem) -> Self {
        let (f, m) = sys.hub_reaction();
        Self {
            stress: nodal_stress(sys),
            contact: sys.contact_samples(),
            hub: HubLoads {
                force: [f[0], f[1]],
                torque: m,
            },
            energy: energy(sys),
        }
    }

    pub fn view<'a>(
        &'a self,
        sys: &'a SolidSystem,
        scalars: &'a [(&'static str, f64)],
    ) -> StepView<'a> {
        StepView {
            mesh: Some(&sys.model.mesh),
            x: &sys.x,
            stress: &self.stress,
            contact: &self.contact,
            hub: Some(self.hub),
            energy: Some(self.energy),
            road_height: sys.road_height(),
            omega: sys.model.omega2.max(0.0).sqrt(),
            scalars,
        }
    }
}

/// Nodal Cauchy stress `[σ11, σ22, σ12]`, averaged over the cells sharing each node.
pub fn nodal_stress(sys: &SolidSystem) -> Vec<[f64; 3]> {
    nodal_stress_at(sys, &sys.x)
}

/// [`nodal_stress`] of the state `x` (full vector, same layout as `sys.x`).
pub fn nodal_stress_at(sys: &SolidSystem, x: &[f64]) -> Vec<[f64; 3]> {
    let mesh = &sys.model.mesh;
    let mut sum = vec![[0.0; 3]; mesh.n_nodes()];
    let mut count = vec![0u32; mesh.n_nodes()];
    for c in 0..mesh.n_cells() {
        let p = mesh.degree[c] as usize;
        let nodes = mesh.cell_nodes(c);
        for j in 0..=p {
            for i in 0..=p {
                let xi = -1.0 + 2.0 * i as f64 / p as f64;
                let eta = -1.0 + 2.0 * j as f64 / p as f64;
                if let Some(pv) = sys.model.point_values(c, &sys.dofs, x, xi, eta) {
                    let s = pv.sigma;
                    if s.iter().all(|v| v.is_finite()) {
                        let n = nodes[i + (p + 1) * j] as usize;
                        sum[n][0] += s[(0, 0)];
                        sum[n][1] += s[(1, 1)];
                        sum[n][2] += 0.5 * (s[(0, 1)] + s[(1, 0)]);
                        count[n] += 1;
                    }
                }
            }
        }
    }
    for (s, &k) in sum.iter_mut().zip(&count) {
        if k > 0 {
            for v in s.iter_mut() {
                *v /= f64::from(k);
            }
        }
    }
    sum
}

/// Strain and kinetic energy (per unit thickness).
pub fn energy(sys: &SolidSystem) -> Energy {
    let model = &sys.model;
    let rule = QuadRule::gauss_2d(3);
    let omega2 = model.omega2.max(0.0);
    let mut e = Energy::default();
    for c in 0..model.mesh.n_cells() {
        let w0 = model.material_of(c).energy(&Mat2::zeros());
        for (pt, w) in rule.points.iter().zip(&rule.weights) {
            if let Some(pv) = model.point_values(c, &sys.dofs, &sys.x, pt.0, pt.1) {
                let dv = pv.jac.determinant() * w;
                let wv = model.material_of(c).energy(&pv.grad_u) - w0;
                if wv.is_finite() {
                    e.strain += wv * dv;
                }
                if omega2 > 0.0 {
                    let t = Vec2::new(-pv.x[1], pv.x[0]);
                    let v = (Mat2::identity() + pv.grad_u) * t;
                    e.kinetic += 0.5 * model.rho_of(c) * omega2 * v.norm_squared() * dv;
                }
            }
        }
    }
    e
}
