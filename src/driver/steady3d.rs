//! Steady rolling of the three-dimensional body in the θ-referential description: the body
//! turns at ω about +x3 (the axle), the road x2 = −H moves at V = v0 (cos α, −sin α) in its
//! plane (α the slip angle, [`crate::model::system3d::road_velocity_3d`]), and the unknown is the motion
//! χ = X + u of the material point at each referential position. The residual is the solid's
//! with the inertia −ω² ∫ ρ ∂θχ · ∂θη ([`crate::model::kernel`]) plus the road contact with
//! the steady velocity v = ω ∂θχ ([`crate::contact::facet3d::Kinematics3D::Steady`]): normal
//! compliance with damping on δ̇ = −v2 and friction on the slip w = (v1 − V1, v3 − V3).
//!
//! As in the plane-strain steady mode, the road is brought in by load stepping at the final
//! ω and road velocity: displacement control H = Ro − λ DISP, or load control (H unknown,
//! ∫ t_n dA0 = λ · load). The forces are those of the road on the body at the hub centre:
//! F = (F1 longitudinal, F2 vertical, F3 lateral) and M = (M1 overturning, M2 aligning
//! (about the vertical), M3 drive torque about the axle), totals over the width.
//!
//! After the press-in, the rolling controls of the plane-strain steady mode apply
//! ([`apply_control_3d`]): torque control and free rolling solve for the road speed v0 at
//! which the hub's torque about the axle is the given one (0), creep control sets
//! v0 = (1 + ξ) v0_free from the free-rolling speed; the slip angle stays, so the longitudinal
//! creep is that of the road speed, V = v0 (cos α, −sin α).

use super::indentation3d::contact_force_scale_3d;
use super::results::ControlReport;
use super::steady::RoadSpeedSystem;
use super::steady_solve::{control_road_speed, speed_control_report};
use crate::io::scene::{ContinuationParameter, ContinuationSpec, Control, Scene};
use crate::model::Solid3DSystem;
use crate::solver::continuation::{
    BranchPoint, Continuation, ContinuationOptions, ContinuationReport, ParametricSystem,
};
use crate::solver::observe::StepObserver;
use crate::solver::stepping::{solve_load_steps, StepOptions, StepReport};
use crate::solver::{LinearKind, Newton, NewtonOptions, NonlinearSystem, SolveError};

/// Solve the steady rolling of `sys` (built with contact and
/// [`Solid3DSystem::set_steady_rolling`]) to λ = 1.
pub fn solve_steady_3d<O: StepObserver<Solid3DSystem> + ?Sized>(
    sys: &mut Solid3DSystem,
    kind: LinearKind,
    newton_opts: NewtonOptions,
    step_opts: &StepOptions,
    report: &mut StepReport,
    rec: &mut O,
) -> Result<(), SolveError> {
    sys.set_reference_force(contact_force_scale_3d(sys));
    let mut newton = Newton::new(sys, kind, newton_opts)?;
    solve_load_steps(sys, &mut newton, step_opts, report, rec)
}

impl RoadSpeedSystem for Solid3DSystem {
    fn road_speed(&self) -> f64 {
        Solid3DSystem::road_speed(self)
    }
    fn set_road_speed(&mut self, v0: f64) {
        Solid3DSystem::set_road_speed(self, v0)
    }
    fn hub_torque(&self) -> f64 {
        self.hub_reaction().1[2]
    }
    fn rolling_speed(&self) -> f64 {
        let ro = self.contact.as_ref().map_or(0.0, |c| c.h_touch);
        (self.steady_omega().unwrap_or(0.0) * ro).abs()
    }
    fn angular_speed(&self) -> f64 {
        self.steady_omega().unwrap_or(0.0)
    }
}

/// The scene's rolling control (`motion.control`) after the press-in of
/// [`solve_steady_3d`], as in the plane-strain steady mode
/// ([`super::steady_solve::control_road_speed`]): torque control and free rolling move the
/// road speed v0 (the slip angle kept) until the torque of the hub about the axle
/// ([`Solid3DSystem::hub_reaction`], moment component 3, a total over the width) equals
/// `motion.torque` or 0; creep control solves free rolling first and then steps
/// v0 = (1 + ξ) v0_free. The torque tolerance is [`super::steady_solve::TORQUE_RTOL`] ·
/// |F_hub| · Ro at the press-in state.
pub fn apply_control_3d(
    scene: &Scene,
    sys: &mut Solid3DSystem,
    kind: LinearKind,
    newton_opts: NewtonOptions,
) -> Result<ControlReport, SolveError> {
    if scene.motion.control == Control::Speed {
        return Ok(speed_control_report());
    }
    let mut newton = Newton::new(sys, kind, newton_opts)?;
    let (f, _) = sys.hub_reaction();
    let ro = sys.contact.as_ref().map_or(0.0, |c| c.h_touch);
    let scale = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt() * ro;
    control_road_speed(scene, sys, scale, &mut newton)
}

/// The parameter of a continuation of the three-dimensional steady state (`[continuation]
/// parameter`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Path3DParameter {
    /// The slip angle α in degrees, at a fixed road speed.
    SlipAngle,
    /// The creep ξ = v0 / v0_free − 1 from the free-rolling speed `v0_free`, at fixed ω.
    Creep { v0_free: f64 },
    /// The hub load of load control (a total force).
    Load,
}

impl Path3DParameter {
    /// The path parameter of `[continuation] parameter`; the creep needs the free-rolling
    /// speed `v0_free` (from the creep or free-rolling control, else NaN). `None` for the
    /// parameters the three-dimensional steady mode does not continue in (ω, the penetration)
    /// and for the creep without a free-rolling speed.
    pub fn of(p: ContinuationParameter, v0_free: f64) -> Option<Self> {
        match p {
            ContinuationParameter::SlipAngle => Some(Self::SlipAngle),
            ContinuationParameter::Creep => v0_free.is_finite().then_some(Self::Creep { v0_free }),
            ContinuationParameter::Load => Some(Self::Load),
            ContinuationParameter::Omega | ContinuationParameter::Disp => None,
        }
    }
}

/// The three-dimensional steady system with one of its parameters exposed
/// ([`ParametricSystem`]) for the arc-length continuation.
pub struct SteadyPath3D<'a> {
    pub sys: &'a mut Solid3DSystem,
    pub parameter: Path3DParameter,
}

impl NonlinearSystem for SteadyPath3D<'_> {
    fn n_eq(&self) -> usize {
        self.sys.n_eq()
    }
    fn fields(&self) -> &[u8] {
        self.sys.fields()
    }
    fn field_names(&self) -> &'static [&'static str] {
        self.sys.field_names()
    }
    fn reference_norms(&self) -> Vec<f64> {
        self.sys.reference_norms()
    }
    fn force_scale(&self) -> &[f64] {
        self.sys.force_scale()
    }
    fn state_magnitudes(&self, out: &mut Vec<f64>) {
        self.sys.state_magnitudes(out)
    }
    fn pattern(&self) -> (&[usize], &[usize]) {
        self.sys.pattern()
    }
    fn evaluate(&mut self, with_matrix: bool) -> bool {
        self.sys.evaluate(with_matrix)
    }
    fn residual(&self) -> &[f64] {
        self.sys.residual()
    }
    fn matrix_values(&self) -> &[f64] {
        self.sys.matrix_values()
    }
    fn update(&mut self, alpha: f64, dx: &[f64]) {
        self.sys.update(alpha, dx)
    }
    fn save_state(&self, buf: &mut Vec<f64>) {
        self.sys.save_state(buf)
    }
    fn restore_state(&mut self, buf: &[f64]) {
        self.sys.restore_state(buf)
    }
}

impl ParametricSystem for SteadyPath3D<'_> {
    fn parameter(&self) -> f64 {
        match self.parameter {
            Path3DParameter::SlipAngle => self.sys.slip_angle().to_degrees(),
            Path3DParameter::Creep { v0_free } => self.sys.road_speed() / v0_free - 1.0,
            Path3DParameter::Load => self
                .sys
                .contact
                .as_ref()
                .and_then(|c| c.load)
                .unwrap_or(0.0),
        }
    }
    fn set_parameter(&mut self, lambda: f64) {
        match self.parameter {
            Path3DParameter::SlipAngle => self.sys.set_slip_angle(lambda.to_radians()),
            Path3DParameter::Creep { v0_free } => self.sys.set_road_speed((1.0 + lambda) * v0_free),
            Path3DParameter::Load => {
                if let Some(c) = self.sys.contact.as_mut() {
                    c.load = Some(lambda);
                }
            }
        }
    }
}

/// Follow the steady state of `sys` (converged) in the parameter of `cs` to its target by the
/// Riks–Crisfield arc-length continuation of the plane-strain steady mode
/// ([`crate::solver::continuation`]; arc lengths scaled by the displacement norm of the start
/// and |target − start|), calling `on_point` at the start and at every converged point
/// (`parameter` from [`Path3DParameter::of`]). No
/// bifurcation test function is evaluated (the determinant's sign is still tracked). Returns
/// the continuation's report, also the part before a failure.
pub fn follow_path_3d(
    scene: &Scene,
    cs: &ContinuationSpec,
    parameter: Path3DParameter,
    sys: &mut Solid3DSystem,
    verbose: bool,
    on_point: &mut dyn FnMut(&SteadyPath3D, &BranchPoint) -> bool,
) -> (Option<ContinuationReport>, Result<(), SolveError>) {
    let n_u = sys.dofs.n_u;
    let u_norm = sys.x[..n_u].iter().map(|v| v * v).sum::<f64>().sqrt();
    let mut path = SteadyPath3D { sys, parameter };
    let start = path.parameter();
    let copts = ContinuationOptions {
        target: cs.target,
        direction: if cs.target >= start { 1.0 } else { -1.0 },
        ds0: cs.ds,
        ds_min: cs.ds * 1e-4,
        ds_max: cs.ds_max,
        x_scale: u_norm.max(1e-12 * scene.geometry.ro),
        lambda_scale: (cs.target - start).abs().max(f64::MIN_POSITIVE),
        max_steps: cs.max_steps,
        max_iterations: scene.solver.max_iterations.min(15),
        desired_iterations: cs.desired_iterations,
        max_cutbacks: scene.solver.max_cutbacks,
        tol: scene.solver.tolerance,
        test_function: false,
        switch_branch: false,
        stop_at_limit: false,
        verbose,
    };
    let mut partial = None;
    let res = Continuation::new(&path, LinearKind::Lu, copts).and_then(|mut c| {
        let r = c.run(&mut path, on_point);
        partial = c.partial.take();
        r
    });
    match res {
        Ok(r) => (Some(r), Ok(())),
        Err(e) => (partial, Err(e)),
    }
}
