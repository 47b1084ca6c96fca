//! The time integrators of the transient mode, registered in one list.
//!
//! Each integrator is a type in its own file implementing [`IntegratorSpec`]
//! ([`super::integrator`]): its scene keyword (`[time] integrator = "…"`), what it is, what it supports (torque control, a
//! quadrature-point history, the consistent mass) and how it integrates a [`Transient`] to the
//! end of the run. [`integrators!`] builds from the list the keyword enum [`IntegratorName`]
//! that the scene holds, with its parsing, its messages and its dispatch; the scene's checks
//! (lumped mass, torque control, history) read the declared properties. A new integrator is
//! its own file (and its `pub mod` line in [`super`]) plus its entry in the list at the end of
//! this file.

use super::integrator::{IntegratorSpec, Setup};
use super::{Scheme, Transient, TransientReport};
use crate::solver::SolveError;

/// Builds, from the list of registered integrator types (`file::Type`, the file a module of
/// [`super`]), the keyword enum [`IntegratorName`] (one variant per type, with the type's
/// name; the first entry is the default) and its dispatch to each type's [`IntegratorSpec`].
macro_rules! integrators {
    ($($file:ident :: $spec:ident),+ $(,)?) => {
        /// Time integrator of the `transient` mode (`[time] integrator`): one of the registered
        /// [`IntegratorSpec`] types; the first registered is the default.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum IntegratorName {
            $(
                #[doc = concat!("[`super::", stringify!($file), "::", stringify!($spec), "`].")]
                $spec,
            )+
        }

        impl IntegratorName {
            /// Every integrator, in registration order.
            pub const ALL: &'static [IntegratorName] = &[$(IntegratorName::$spec),+];
            /// The scene keyword of every integrator, in registration order.
            pub const NAMES: &'static [&'static str] = &[$(<super::$file::$spec as IntegratorSpec>::NAME),+];

            /// The scene keyword.
            pub fn as_str(self) -> &'static str {
                match self {
                    $(IntegratorName::$spec => <super::$file::$spec as IntegratorSpec>::NAME,)+
                }
            }

            /// What it is ([`IntegratorSpec::ABOUT`]).
            pub fn about(self) -> &'static str {
                match self {
                    $(IntegratorName::$spec => <super::$file::$spec as IntegratorSpec>::ABOUT,)+
                }
            }

            /// See [`IntegratorSpec::LUMPED_ONLY`].
            pub fn lumped_only(self) -> bool {
                match self {
                    $(IntegratorName::$spec => <super::$file::$spec as IntegratorSpec>::LUMPED_ONLY,)+
                }
            }

            /// See [`IntegratorSpec::TORQUE_CONTROL`].
            pub fn torque_control(self) -> bool {
                match self {
                    $(IntegratorName::$spec => <super::$file::$spec as IntegratorSpec>::TORQUE_CONTROL,)+
                }
            }

            /// See [`IntegratorSpec::HISTORY`].
            pub fn carries_history(self) -> bool {
                match self {
                    $(IntegratorName::$spec => <super::$file::$spec as IntegratorSpec>::HISTORY,)+
                }
            }

            /// See [`IntegratorSpec::BOUNDED_STEP`].
            pub fn bounded_step(self) -> bool {
                match self {
                    $(IntegratorName::$spec => <super::$file::$spec as IntegratorSpec>::BOUNDED_STEP,)+
                }
            }

            /// See [`IntegratorSpec::RHO_INF_MIN`].
            pub fn rho_inf_min(self) -> f64 {
                match self {
                    $(IntegratorName::$spec => <super::$file::$spec as IntegratorSpec>::RHO_INF_MIN,)+
                }
            }

            /// See [`IntegratorSpec::scheme`].
            pub fn scheme(self, rho_inf: f64) -> Scheme {
                match self {
                    $(IntegratorName::$spec => <super::$file::$spec as IntegratorSpec>::scheme(rho_inf),)+
                }
            }

            /// See [`IntegratorSpec::scheme_3d`].
            pub fn scheme_3d(self, rho_inf: f64) -> Option<Scheme<crate::model::Solid3DSystem>> {
                match self {
                    $(IntegratorName::$spec => <super::$file::$spec as IntegratorSpec>::scheme_3d(rho_inf),)+
                }
            }

            /// See [`IntegratorSpec::integrate`].
            #[allow(clippy::result_large_err)]
            pub fn integrate(
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

impl Default for IntegratorName {
    fn default() -> Self {
        IntegratorName::ALL[0]
    }
}

impl IntegratorName {
    /// The scene keywords of the registered integrators for which `has` holds, quoted and
    /// joined by "or" (for messages: `"generalized_alpha" or "central_difference"`).
    pub fn quoted_with(has: impl Fn(IntegratorName) -> bool) -> String {
        let names: Vec<String> = Self::ALL
            .iter()
            .filter(|i| has(**i))
            .map(|i| format!("\"{i}\""))
            .collect();
        names.join(" or ")
    }
}

impl std::fmt::Display for IntegratorName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for IntegratorName {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let s = s.trim();
        Self::ALL
            .iter()
            .copied()
            .find(|i| i.as_str() == s)
            .ok_or_else(|| {
                let names: Vec<String> = Self::NAMES.iter().map(|n| format!("\"{n}\"")).collect();
                format!(
                    "unknown time integrator \"{s}\"; expected one of {}",
                    names.join(", ")
                )
            })
    }
}

impl serde::Serialize for IntegratorName {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

impl<'de> serde::Deserialize<'de> for IntegratorName {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = <String as serde::Deserialize>::deserialize(d)?;
        s.parse().map_err(serde::de::Error::custom)
    }
}

integrators!(
    generalized_alpha::GeneralizedAlpha,
    central_difference::CentralDifference,
    bdf::Bdf,
    sdirk::Sdirk,
    hht_alpha::HhtAlpha,
);
