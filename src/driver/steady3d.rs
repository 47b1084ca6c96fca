//! Steady rolling of the three-dimensional body in the θ-referential description: the body
//! turns at ω about +x3 (the axle), the road x2 = −H moves at V = v0 (cos α, −sin α) in its
//! plane (α the slip angle, [`crate::setup::road_velocity_3d`]), and the unknown is the motion
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

use super::indentation3d::contact_force_scale_3d;
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
