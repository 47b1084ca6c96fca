//! Steady spinning of the three-dimensional body: A(χ, η) = ω² B(χ, η) with the hub surface
//! bonded (all components fixed), other constraints as the caller fixes them (e.g. u3 = 0 on
//! both flat faces for the plane-strain slab), ω² reached by load stepping, as in
//! [`super::spinning`].

use crate::model::{Coefficients, Solid3DSystem};
use crate::solver::observe::StepObserver;
use crate::solver::stepping::{solve_load_steps, StepOptions, StepReport};
use crate::solver::{LinearKind, Newton, NewtonOptions, NonlinearSystem, SolveError};

/// Drive ω from 0 to `omega` by load steps in ω².
pub fn solve_spinning_3d<O: StepObserver<Solid3DSystem> + ?Sized>(
    sys: &mut Solid3DSystem,
    omega: f64,
    kind: LinearKind,
    newton_opts: NewtonOptions,
    step_opts: &StepOptions,
    report: &mut StepReport,
    rec: &mut O,
) -> Result<(), SolveError> {
    let target = Coefficients {
        omega2: omega * omega,
        ..sys.coefficients
    };
    sys.set_target(target);
    // Reference force: the centrifugal load at the target speed on the undeformed body.
    let x0 = sys.x.clone();
    let mut zero = x0.clone();
    zero[..sys.dofs.n_u].fill(0.0);
    sys.x.copy_from_slice(&zero);
    sys.coefficients = target;
    sys.evaluate(false);
    let f_spin = norm(sys.residual());
    sys.coefficients = Coefficients::default();
    sys.evaluate(false);
    let f_rest = norm(sys.residual());
    sys.x.copy_from_slice(&x0);
    sys.set_reference_force((f_spin - f_rest).abs().max(f_rest).max(f64::MIN_POSITIVE));
    let mut newton = Newton::new(sys, kind, newton_opts)?;
    solve_load_steps(sys, &mut newton, step_opts, report, rec)
}

fn norm(r: &[f64]) -> f64 {
    r.iter().map(|v| v * v).sum::<f64>().sqrt()
}
