//! The time integrators of the transient mode, registered against their names.
//!
//! Each integrator is a type in its own file implementing [`IntegratorSpec`]
//! ([`super::integrator`]): how it integrates a [`Transient`] to the end of the run, and the
//! one-step scheme it builds the model with. Its name and what it declares (lumped mass only,
//! torque control, history, the least `rho_inf`, 3D) are its row of
//! [`crate::solver::integrators::IntegratorName`], which the scene holds and checks.
//! [`integrators!`] builds from the list at the end of this file the dispatch [`Integrate`]
//! on the names, an exhaustive match: every name needs a type here, every type a name. A new
//! integrator is its name's row, its own file (and its `pub mod` line in [`super`]) and its
//! entry in the list.

use super::integrator::{IntegratorSpec, Setup};
use super::{Scheme, Transient, TransientReport};
pub use crate::solver::integrators::IntegratorName;
use crate::solver::SolveError;

/// What an integrator's name does in the transient driver: the registered type's
/// [`IntegratorSpec`].
pub trait Integrate {
    /// See [`IntegratorSpec::scheme`].
    fn scheme(self, rho_inf: f64) -> Scheme;
    /// See [`IntegratorSpec::scheme_3d`] (`Some` exactly for the names that declare
    /// [`IntegratorName::three_d`]).
    fn scheme_3d(self, rho_inf: f64) -> Option<Scheme<crate::model::Solid3DSystem>>;
    /// See [`IntegratorSpec::integrate`].
    #[allow(clippy::result_large_err)]
    fn integrate(
        self,
        tr: &mut Transient,
        setup: &Setup,
        on_step: &mut dyn FnMut(&Transient, &TransientReport),
    ) -> Result<TransientReport, (SolveError, TransientReport)>;
}

/// Builds, from the list of registered integrator types (`file::Type`, the file a module of
/// [`super`], the type named as its [`IntegratorName`] variant), the dispatch [`Integrate`].
macro_rules! integrators {
    ($($file:ident :: $spec:ident),+ $(,)?) => {
        impl Integrate for IntegratorName {
            fn scheme(self, rho_inf: f64) -> Scheme {
                match self {
                    $(IntegratorName::$spec => <super::$file::$spec as IntegratorSpec>::scheme(rho_inf),)+
                }
            }

            fn scheme_3d(self, rho_inf: f64) -> Option<Scheme<crate::model::Solid3DSystem>> {
                match self {
                    $(IntegratorName::$spec => <super::$file::$spec as IntegratorSpec>::scheme_3d(rho_inf),)+
                }
            }

            fn integrate(
                self,
                tr: &mut Transient,
                setup: &Setup,
                on_step: &mut dyn FnMut(&Transient, &TransientReport),
            ) -> Result<TransientReport, (SolveError, TransientReport)> {
                match self {
                    $(IntegratorName::$spec => <super::$file::$spec as IntegratorSpec>::integrate(tr, setup, on_step),)+
                }
            }
        }
    };
}

integrators!(
    generalized_alpha::GeneralizedAlpha,
    central_difference::CentralDifference,
    bdf::Bdf,
    sdirk::Sdirk,
    hht_alpha::HhtAlpha,
);

#[cfg(test)]
mod tests {
    use super::*;

    /// The 3D declaration matches what the registered types build.
    #[test]
    fn three_d_is_declared_by_exactly_the_integrators_with_a_3d_scheme() {
        for i in IntegratorName::ALL {
            assert_eq!(i.three_d(), i.scheme_3d(0.8).is_some(), "{i}");
        }
    }
}
