//! Static indentation of the three-dimensional body: the road raised into it (displacement
//! control, H = h_touch − λ · disp) or the body pressed onto the road by a hub load (load
//! control, H unknown, λ · load = ∫ t_n dA0), by load stepping in λ with cut-back, as
//! [`super::indentation`] does in plane strain. No inertia (ω = 0). Forces are totals (not per
//! width).

use crate::model::Solid3DSystem;
use crate::solver::observe::StepObserver;
use crate::solver::stepping::{solve_load_steps, StepOptions, StepReport};
use crate::solver::{LinearKind, Newton, NewtonOptions, SolveError};

/// Floor of the displacement field's convergence reference (see [`crate::solver::newton`]),
/// as the plane-strain program's: the hub load under load control; under displacement control
/// the series combination F_c F_b / (F_c + F_b) of the penalty-limited force
/// F_c = c_n DISP^m_n √(2 Ro DISP) W and the body-limited force F_b = G DISP W (G the
/// small-strain shear modulus, W the body's extent along the axle, Ro = h_touch). 1 without
/// contact.
pub fn contact_force_scale_3d(sys: &Solid3DSystem) -> f64 {
    let Some(rc) = sys.contact.as_ref() else {
        return 1.0;
    };
    let f = match rc.load {
        Some(load) => load.abs(),
        None => {
            let (lo, hi) = sys
                .solid
                .mesh
                .nodes
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                    (a.min(x[2]), b.max(x[2]))
                });
            let width = (hi - lo).max(0.0);
            let disp = rc.disp.abs();
            let g = sys.solid.material.small_strain_shear_modulus().abs();
            let fb = g * disp * width;
            let n = rc.surface.normal;
            let fc =
                n.c_n.abs() * disp.powf(n.m_n) * (2.0 * rc.h_touch.abs() * disp).sqrt() * width;
            if fc + fb > 0.0 {
                fc * fb / (fc + fb)
            } else {
                0.0
            }
        }
    };
    f.max(f64::MIN_POSITIVE)
}

/// Solve the static indentation to λ = 1.
pub fn solve_indentation_3d<O: StepObserver<Solid3DSystem> + ?Sized>(
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
