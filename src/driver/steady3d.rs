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
use super::steady_report::CoarseStart;
use super::steady_solve::{control_road_speed, speed_control_report};
use crate::io::scene::{ContinuationParameter, ContinuationSpec, Control, Scene};
use crate::model::Solid3DSystem;
use crate::solver::continuation::{
    BranchPoint, Continuation, ContinuationOptions, ContinuationReport, ParametricSystem,
};
use crate::solver::observe::StepObserver;
use crate::solver::stepping::{solve_load_steps, LoadedSystem, StepOptions, StepReport};
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
    /// The camber γ in degrees (the road height of first touch follows it).
    Camber,
    /// The creep ξ = v0 / v0_free − 1 from the free-rolling speed `v0_free`, at fixed ω.
    Creep { v0_free: f64 },
    /// The hub load of load control (a total force).
    Load,
    /// The angular speed ω (rad/s), with the road speed v0 = `v0_per_omega` ω (the creep and
    /// the slip angle fixed), as the plane-strain continuation in ω.
    Omega { v0_per_omega: f64 },
    /// The penetration h_touch − H of displacement control (length).
    Disp,
}

impl Path3DParameter {
    /// The path parameter of `[continuation] parameter` for the converged steady system
    /// `sys`; the creep needs the free-rolling speed `v0_free` (from the creep or free-rolling
    /// control, else NaN). `None` for the creep without a free-rolling speed, for the load
    /// under displacement control, for the penetration under load control and for ω at rest.
    pub fn of(p: ContinuationParameter, v0_free: f64, sys: &Solid3DSystem) -> Option<Self> {
        let load_control = sys.contact.as_ref().is_some_and(|c| c.h_dof.is_some());
        match p {
            ContinuationParameter::SlipAngle => Some(Self::SlipAngle),
            ContinuationParameter::Camber => Some(Self::Camber),
            ContinuationParameter::Creep => v0_free.is_finite().then_some(Self::Creep { v0_free }),
            ContinuationParameter::Load => load_control.then_some(Self::Load),
            ContinuationParameter::Omega => {
                let omega = sys.steady_omega().filter(|w| *w != 0.0)?;
                Some(Self::Omega {
                    v0_per_omega: sys.road_speed() / omega,
                })
            }
            ContinuationParameter::Disp => (!load_control).then_some(Self::Disp),
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
    crate::solver::system::delegate_nonlinear_system!(sys);
}

impl ParametricSystem for SteadyPath3D<'_> {
    fn parameter(&self) -> f64 {
        match self.parameter {
            Path3DParameter::SlipAngle => self.sys.slip_angle().to_degrees(),
            Path3DParameter::Camber => self.sys.camber().to_degrees(),
            Path3DParameter::Creep { v0_free } => self.sys.road_speed() / v0_free - 1.0,
            Path3DParameter::Load => self
                .sys
                .contact
                .as_ref()
                .and_then(|c| c.load)
                .unwrap_or(0.0),
            Path3DParameter::Omega { .. } => self.sys.steady_omega().unwrap_or(0.0),
            Path3DParameter::Disp => self.sys.penetration().unwrap_or(0.0),
        }
    }
    fn set_parameter(&mut self, lambda: f64) {
        match self.parameter {
            Path3DParameter::SlipAngle => self.sys.set_slip_angle(lambda.to_radians()),
            Path3DParameter::Camber => {
                // |γ| ≥ 90° leaves the frame as it was (the corrector then fails there).
                let _ = self.sys.set_camber(lambda.to_radians());
            }
            Path3DParameter::Creep { v0_free } => self.sys.set_road_speed((1.0 + lambda) * v0_free),
            Path3DParameter::Load => {
                if let Some(c) = self.sys.contact.as_mut() {
                    c.load = Some(lambda);
                }
            }
            Path3DParameter::Omega { v0_per_omega } => {
                self.sys.set_steady_omega(lambda);
                self.sys.set_road_speed(v0_per_omega * lambda);
            }
            Path3DParameter::Disp => self.sys.set_penetration(lambda),
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
        test_function: false,
        switch_branch: false,
        stop_at_limit: false,
        ..crate::setup::continuation_options(scene, cs, start, u_norm, verbose)
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

/// The scene on the mesh with half the cells in θ (and in r and along the axle where their
/// counts are even) for the nested iteration of [`solve_steady_3d_nested`]: `[solver]
/// coarse_start`, a generated revolved mesh with n_theta a multiple of 4 ≥ 64 (the coarse mesh
/// keeps n_theta even and ≥ 32).
pub fn coarse_scene_3d(scene: &Scene) -> Option<Scene> {
    let m = &scene.mesh;
    let applies = scene.solver.coarse_start
        && m.file.is_none()
        && m.n_theta >= 64
        && m.n_theta.is_multiple_of(4);
    applies.then(|| {
        let mut c = scene.clone();
        c.mesh.n_theta /= 2;
        if c.mesh.n_r >= 2 && c.mesh.n_r.is_multiple_of(2) {
            c.mesh.n_r /= 2;
        }
        let n_z = c.mesh.resolved_n_z();
        if n_z >= 2 && n_z.is_multiple_of(2) {
            c.mesh.n_z = Some(n_z / 2);
        }
        c
    })
}

/// The steady state of `sys` (the scene's system) by the nested iteration where it applies
/// ([`coarse_scene_3d`]): the coarser mesh's steady state (solved the same way, so it starts
/// from its own coarser mesh in turn) interpolated to this mesh's nodes (the displacements, and
/// the road height under load control; [`crate::mesh::locate3d`]), then Newton at full load
/// from there. Most of the Newton iterations of a press-in from the undeformed state find the
/// contact patch with damped steps; on the coarse mesh they are cheap. If the coarse solve or
/// Newton from the interpolated state fails, the state is restored and the road is pressed in
/// from the undeformed state ([`solve_steady_3d`]). Returns what the nested iteration did
/// (`None` where it does not apply).
pub fn solve_steady_3d_nested<O: StepObserver<Solid3DSystem> + ?Sized>(
    scene: &Scene,
    sys: &mut Solid3DSystem,
    kind: LinearKind,
    newton_opts: NewtonOptions,
    step_opts: &StepOptions,
    report: &mut StepReport,
    rec: &mut O,
) -> (Option<CoarseStart>, Result<(), SolveError>) {
    let Some(coarse) = coarse_scene_3d(scene) else {
        return (
            None,
            solve_steady_3d(sys, kind, newton_opts, step_opts, report, rec),
        );
    };
    let t0 = std::time::Instant::now();
    let name = format!(
        "{}x{}x{}",
        coarse.mesh.n_r,
        coarse.mesh.resolved_n_z(),
        coarse.mesh.n_theta
    );
    let mut out = CoarseStart::default();
    let mut undeformed = Vec::new();
    sys.save_state(&mut undeformed);
    let solved = crate::setup::build_system_3d(&coarse)
        .map_err(|e| format!("the {name} mesh could not be built: {e}"))
        .and_then(|mut csys| {
            let ckind = crate::setup::linear_kind_3d(&coarse, &csys);
            let (cnewton, csteps) = crate::setup::solver_options(&coarse, false);
            let mut crep = StepReport::default();
            let (inner, res) = solve_steady_3d_nested(
                &coarse,
                &mut csys,
                ckind,
                cnewton,
                &csteps,
                &mut crep,
                &mut crate::solver::observe::NoObserver,
            );
            if let Some(inner) = inner {
                out.meshes = inner.meshes;
                out.coarse_newton_iterations = inner.coarse_newton_iterations;
            }
            out.coarse_newton_iterations += crep.total_iterations;
            res.map(|()| csys)
                .map_err(|e| format!("the solve on the {name} mesh failed: {e}"))
        });
    out.meshes.push(name);
    let csys = match solved {
        Ok(c) => c,
        Err(e) => {
            out.coarse_wall_time_s = t0.elapsed().as_secs_f64();
            out.error = Some(e);
            return (
                Some(out),
                solve_steady_3d(sys, kind, newton_opts, step_opts, report, rec),
            );
        }
    };
    let interpolated = interpolate_state_3d(&csys, sys);
    drop(csys);
    if let Err(e) = interpolated {
        out.coarse_wall_time_s = t0.elapsed().as_secs_f64();
        out.error = Some(format!("interpolation from the coarse mesh: {e}"));
        sys.restore_state(&undeformed);
        return (
            Some(out),
            solve_steady_3d(sys, kind, newton_opts, step_opts, report, rec),
        );
    }
    out.coarse_wall_time_s = t0.elapsed().as_secs_f64();
    if newton_opts.verbose {
        eprintln!(
            "  started from the steady state on the {} mesh ({} Newton iterations, {:.3} s)",
            out.meshes.join(" -> "),
            out.coarse_newton_iterations,
            out.coarse_wall_time_s
        );
    }
    sys.set_reference_force(contact_force_scale_3d(sys));
    sys.set_load(1.0);
    let res = Newton::new(sys, kind, newton_opts.clone()).and_then(|mut n| n.solve(sys));
    match res {
        Ok(r) => {
            sys.commit();
            out.newton_iterations = r.iterations;
            out.succeeded = true;
            report.total_iterations += r.iterations;
            report.steps.push(crate::solver::stepping::StepRecord {
                lambda: 1.0,
                converged: true,
                iterations: r.iterations,
                table: r.table.clone(),
                timing: r.timing,
            });
            rec.observe_newton(0, 1.0, &r.table, sys.field_names());
            rec.observe_accepted(
                sys,
                &crate::solver::StepInfo {
                    index: 0,
                    time: 1.0,
                    dt: 1.0,
                    newton_iterations: r.iterations,
                    residual: 0.0,
                    is_final: true,
                },
            );
            (Some(out), Ok(()))
        }
        Err(e @ SolveError::Interrupted { .. }) => (Some(out), Err(e)),
        Err(e) => {
            if newton_opts.verbose {
                eprintln!(
                    "  Newton from the interpolated state failed ({e}): pressing in from the undeformed state"
                );
            }
            out.error = Some(format!("Newton from the interpolated state: {e}"));
            sys.restore_state(&undeformed);
            sys.set_load(0.0);
            (
                Some(out),
                solve_steady_3d(sys, kind, newton_opts, step_opts, report, rec),
            )
        }
    }
}

/// Interpolate the displacements of `from` (a coarser revolved mesh of the same body) to the
/// nodes of `to`, and copy its global unknowns (the road height under load control). Fails
/// when a node of `to` lies outside `from`'s mesh or a mesh has no ring layout.
fn interpolate_state_3d(from: &Solid3DSystem, to: &mut Solid3DSystem) -> Result<(), String> {
    use crate::assembly::CONSTRAINED;
    let src = &from.solid.mesh;
    let found = crate::mesh::locate3d::locate_points_revolved(src, &to.solid.mesh.nodes)
        .ok_or("the coarse mesh has no ring layout")?;
    let mut x = to.x.clone();
    for (a, f) in found.iter().enumerate() {
        let (c, xi) = f.ok_or_else(|| {
            let p = to.solid.mesh.nodes[a];
            format!(
                "node {a} at ({:.4}, {:.4}, {:.4}) is outside the coarse mesh",
                p[0], p[1], p[2]
            )
        })?;
        let u = crate::mesh::locate3d::vector_at(src, &from.x, c, xi);
        for (i, &ui) in u.iter().enumerate() {
            if to.dofs.eq[3 * a + i] < CONSTRAINED {
                x[3 * a + i] = ui;
            }
        }
    }
    for k in 0..to.dofs.n_global.min(from.dofs.n_global) {
        x[to.dofs.global(k)] = from.x[from.dofs.global(k)];
    }
    to.restore_state(&x);
    Ok(())
}
