//! SDIRK (diffsol's ESDIRK34) on the first-order form y = (u, v) of the transient model
//! ([`super::ode_first_order`]).

use super::integrator::{IntegratorSpec, Setup};
use super::ode_first_order::{integrate_first_order, OdeMethod};
use super::{Transient, TransientReport};
use crate::solver::SolveError;

/// The scene's `"sdirk"`: [`integrate_first_order`] with [`OdeMethod::Esdirk34`].
pub struct Sdirk;

impl IntegratorSpec for Sdirk {
    fn integrate(
        tr: &mut Transient,
        setup: &Setup,
        on_step: &mut dyn FnMut(&Transient, &TransientReport),
    ) -> Result<TransientReport, (SolveError, TransientReport)> {
        integrate_first_order(tr, OdeMethod::Esdirk34, &setup.time, setup.ode_tol, on_step)
    }
}
