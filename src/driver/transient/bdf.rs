//! Variable-order BDF (diffsol) on the first-order form y = (u, v) of the transient model
//! ([`super::ode_first_order`]).

use super::integrator::{IntegratorSpec, Setup};
use super::ode_first_order::{integrate_first_order, OdeMethod};
use super::{Transient, TransientReport};
use crate::solver::SolveError;

/// The scene's `"bdf"`: [`integrate_first_order`] with [`OdeMethod::Bdf`].
pub struct Bdf;

impl IntegratorSpec for Bdf {
    fn integrate(
        tr: &mut Transient,
        setup: &Setup,
        on_step: &mut dyn FnMut(&Transient, &TransientReport),
    ) -> Result<TransientReport, (SolveError, TransientReport)> {
        integrate_first_order(tr, OdeMethod::Bdf, &setup.time, setup.ode_tol, on_step)
    }
}
