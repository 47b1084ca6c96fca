//! What a time integrator of the transient mode declares and does ([`IntegratorSpec`]); the
//! list of integrators is in [`super::registry`].

use super::ode_first_order::OdeTolerances;
use super::{integrate, GenAlpha, Scheme, TimeOptions, Transient, TransientReport};
use crate::solver::{LinearKind, NewtonOptions, SolveError};

/// Everything a run hands to an integrator besides the model: the step and stopping options,
/// the Newton options and linear solver of the implicit steps, and the tolerances of the
/// first-order (diffsol) integrators.
#[derive(Clone, Debug)]
pub struct Setup {
    pub time: TimeOptions,
    pub newton: NewtonOptions,
    pub linear: LinearKind,
    pub ode_tol: OdeTolerances,
}

/// A registered time integrator: what it does (its name and declarations are its row of
/// [`crate::solver::integrators::IntegratorName`]).
pub trait IntegratorSpec {
    /// The one-step scheme the [`Transient`] model is built with (its Newton system). By
    /// default generalized-α with `rho_inf`, which an integrator with its own loop (BDF, SDIRK)
    /// leaves unused.
    fn scheme(rho_inf: f64) -> Scheme {
        Scheme::generalized_alpha(GenAlpha::new(rho_inf))
    }

    /// The one-step scheme of the three-dimensional solid, when the integrator runs in 3D
    /// (the one-step loop of [`integrate`] on [`crate::model::Solid3DSystem`]); `None` by
    /// default.
    fn scheme_3d(_rho_inf: f64) -> Option<Scheme<crate::model::Solid3DSystem>> {
        None
    }

    /// Integrate from the committed state to the end of the run, calling `on_step` after every
    /// accepted step. On failure the model holds the last accepted step. By default the
    /// one-step loop of [`integrate`] (passages, steady-state detection, step control) with
    /// [`Self::scheme`]'s step.
    // The report of a failed run comes back with its error, once per run.
    #[allow(clippy::result_large_err)]
    fn integrate(
        tr: &mut Transient,
        setup: &Setup,
        on_step: &mut dyn FnMut(&Transient, &TransientReport),
    ) -> Result<TransientReport, (SolveError, TransientReport)> {
        integrate(tr, &setup.time, setup.newton.clone(), setup.linear, on_step)
    }
}
