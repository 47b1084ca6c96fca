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
use crate::io::scene::{Control, Scene};
use crate::model::Solid3DSystem;
use crate::solver::observe::StepObserver;
use crate::solver::stepping::{solve_load_steps, StepOptions, StepReport};
use crate::solver::{LinearKind, Newton, NewtonOptions, SolveError};

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
