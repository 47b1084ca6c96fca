//! [`SolidFrame`]: what the recorder sees of a [`SolidSystem`] at a step — nodal Cauchy
//! stresses, contact samples, hub loads and energies — computed only when some sink wants the
//! view ([`crate::io::record::Recorder::wants_view`]).
//!
//! * Nodal stress: the Cauchy stress σ = P Fᵀ/J of each cell evaluated at its nodes and averaged
//!   over the cells sharing a node (discontinuous across cells otherwise); with σ33 of plane
//!   strain and the pressure field of a mixed formulation ([`NodalStress`]).
//! * Recovered nodal stress: superconvergent patch recovery ([`crate::physics::recovery`]).
//! * Strain energy ∫ (W(F) − W(I)) dV and kinetic energy ½ ω² ∫ ρ |F t|² dV (t = (−X2, X1): the
//!   velocity of steady spin is v = ω ∂θχ = ω F t), with the 3×3 Gauss rule per cell.
//! * Hub loads: [`SolidSystem::hub_reaction`].
//!
//! Every recorder is also the solvers' [`StepObserver`] of a [`SolidSystem`]: an accepted step
//! goes to [`SolidSystem::record_step`], the Newton table to the recorder's iteration events,
//! and the interrupt flag answers whether to stop.

use crate::contact::ContactSample;
use crate::element::QuadRule;
use crate::io::record::{self, Energy, HubLoads, Recorder, StepView};
use crate::material::Hyperelastic;
use crate::math::{Mat2, Vec2};
use crate::model::SolidSystem;
use crate::solver::{IterationRecord, RejectedStep, StepInfo, StepObserver};

/// Owned data of a view; [`SolidFrame::view`] lends it out with the system's state.
pub struct SolidFrame {
    pub stress: Vec<[f64; 3]>,
    /// Nodal σ33 (plane strain) and pressure field p (empty without one).
    pub sigma_33: Vec<f64>,
    pub pressure: Vec<f64>,
    /// Recovered nodal Cauchy stress `[σ11, σ22, σ12, σ33]` ([`crate::physics::recovery`]).
    pub stress_recovered: Vec<[f64; 4]>,
    /// Zienkiewicz–Zhu error indicator per cell ([`crate::physics::estimate::recovery`]).
    pub error_indicator: Vec<f64>,
    pub contact: Vec<ContactSample>,
    pub hub: HubLoads,
    pub energy: Energy,
}

impl SolidSystem {
    /// Send the accepted step `info` to the recorder, with a view of the state when the
    /// recorder wants one.
    pub fn record_step<R: Recorder + ?Sized>(&self, info: &StepInfo, rec: &mut R) {
        if rec.wants_view(info) {
            let frame = SolidFrame::capture(self, rec.wants_fields(info));
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

/// The recovered fields of the state `x` of `sys` when `wanted` (the recovered Cauchy stress
/// and the Zienkiewicz–Zhu error indicator per cell: two patch recoveries), else empty.
pub fn recovered_fields(sys: &SolidSystem, x: &[f64], wanted: bool) -> (Vec<[f64; 4]>, Vec<f64>) {
    if !wanted {
        return (Vec::new(), Vec::new());
    }
    rayon::join(
        || crate::physics::recovery::recover_cauchy(&sys.model, &sys.dofs, x),
        || crate::physics::estimate::recovery(&sys.model, &sys.dofs, x).indicators,
    )
}

impl SolidFrame {
    /// The frame of the current state; with `fields`, also the recovered stress and the error
    /// indicator (two patch recoveries; empty otherwise).
    pub fn capture(sys: &SolidSystem, fields: bool) -> Self {
        // The patch recoveries (two thirds of the work) go alongside the rest.
        let ((stress_recovered, error_indicator), (ns, energy, contact, (f, m))) = rayon::join(
            || recovered_fields(sys, &sys.x, fields),
            || {
                (
                    nodal_stress_full_at(sys, &sys.x),
                    energy(sys),
                    sys.contact_samples(),
                    sys.hub_reaction(),
                )
            },
        );
        Self {
            stress: ns.in_plane,
            sigma_33: ns.sigma_33,
            pressure: ns.pressure,
            stress_recovered,
            error_indicator,
            contact,
            hub: HubLoads {
                force: [f[0], f[1]],
                torque: m,
            },
            energy,
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
            sigma_33: &self.sigma_33,
            pressure: &self.pressure,
            stress_recovered: &self.stress_recovered,
            error_indicator: &self.error_indicator,
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
    nodal_stress_full_at(sys, x).in_plane
}

/// Nodal stresses of a state, averaged over the cells sharing each node; NaN at a node where
/// no cell gives a finite value.
pub struct NodalStress {
    /// `[σ11, σ22, σ12]`.
    pub in_plane: Vec<[f64; 3]>,
    /// σ33 of plane strain (`F33 = 1`): the law's out-of-plane stress minus the pressure.
    pub sigma_33: Vec<f64>,
    /// Pressure field p of a mixed (incompressible) formulation, σ = σ_law − p I; empty when the
    /// model has none.
    pub pressure: Vec<f64>,
}

/// [`NodalStress`] of the state `x` (full vector, same layout as `sys.x`).
///
/// The pressure is recovered from the in-plane stress: the element's Cauchy stress is
/// σ = σ_law − p I (the term −p cof F of P gives −p I), so p = tr(σ_law − σ)/2 with
/// σ_law = P_law(∇u) Fᵀ/J.
pub fn nodal_stress_full_at(sys: &SolidSystem, x: &[f64]) -> NodalStress {
    let mesh = &sys.model.mesh;
    let has_p = !matches!(
        sys.model.pressure,
        crate::physics::solid::PressureMode::None
    );
    let nn = mesh.n_nodes();
    // [σ11, σ22, σ12, σ33, p] per node.
    let mut sum = vec![[0.0; 5]; nn];
    let mut count = vec![0u32; nn];
    for c in 0..mesh.n_cells() {
        let p = mesh.degree[c] as usize;
        let nodes = mesh.cell_nodes(c);
        let law = sys.model.material_of(c);
        for j in 0..=p {
            for i in 0..=p {
                let xi = -1.0 + 2.0 * i as f64 / p as f64;
                let eta = -1.0 + 2.0 * j as f64 / p as f64;
                if let Some(pv) = sys.model.point_values(c, &sys.dofs, x, xi, eta) {
                    let s = pv.sigma;
                    let pres = if has_p {
                        let f = Mat2::identity() + pv.grad_u;
                        let sl = law.stress(&pv.grad_u) * f.transpose() / f.determinant();
                        0.5 * (sl - s).trace()
                    } else {
                        0.0
                    };
                    let s33 = law.cauchy_33(&pv.grad_u) - pres;
                    let v = [
                        s[(0, 0)],
                        s[(1, 1)],
                        0.5 * (s[(0, 1)] + s[(1, 0)]),
                        s33,
                        pres,
                    ];
                    if v.iter().all(|v| v.is_finite()) {
                        let n = nodes[i + (p + 1) * j] as usize;
                        for (a, b) in sum[n].iter_mut().zip(v) {
                            *a += b;
                        }
                        count[n] += 1;
                    }
                }
            }
        }
    }
    let mut out = NodalStress {
        in_plane: Vec::with_capacity(nn),
        sigma_33: Vec::with_capacity(nn),
        pressure: Vec::with_capacity(if has_p { nn } else { 0 }),
    };
    for (s, &k) in sum.iter().zip(&count) {
        let m = if k > 0 {
            s.map(|v| v / f64::from(k))
        } else {
            [f64::NAN; 5]
        };
        out.in_plane.push([m[0], m[1], m[2]]);
        out.sigma_33.push(m[3]);
        if has_p {
            out.pressure.push(m[4]);
        }
    }
    out
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
