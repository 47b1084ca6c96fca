//! The time integrators of the transient mode by name: the keyword a scene gives
//! (`[time] integrator = "…"`) and what each integrator declares (what it is, what it
//! supports), read by the scene's checks and its reference. The integrators themselves (how
//! each one advances a model) are types of the transient driver, registered there against
//! these names (`crate::driver::transient::registry`): the dispatch is an exhaustive match
//! on [`IntegratorName`], so a name without an integrator, or an integrator without a name,
//! does not compile.
//!
//! A new integrator is its row in [`IntegratorName::traits`] (and its variant), its type
//! in its own file of the transient driver, and its entry in the driver's registry.

/// What an integrator declares.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IntegratorTraits {
    /// The scene keyword (`[time] integrator`).
    pub name: &'static str,
    /// What it is, for the scene reference.
    pub about: &'static str,
    /// Always uses the lumped mass (an explicit scheme); a scene's `mass = "consistent"` is
    /// then an error.
    pub lumped_only: bool,
    /// Solves the hub angle as an unknown (torque control).
    pub torque_control: bool,
    /// Carries a quadrature-point history (viscoelastic materials).
    pub history: bool,
    /// Smallest admissible `[time] rho_inf` (the spectral radius at infinity, at most 1; read
    /// only by the integrators that have one).
    pub rho_inf_min: f64,
    /// Its steps never exceed `[time] dt_max` (adaptive steps) or `dt` (fixed steps); false
    /// for an integrator that chooses its own steps without a maximum.
    pub bounded_step: bool,
    /// Runs on the three-dimensional solid.
    pub three_d: bool,
}

/// Time integrator of the `transient` mode (`[time] integrator`); the first is the default.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum IntegratorName {
    /// Generalized-α (Chung–Hulbert).
    GeneralizedAlpha,
    /// Explicit central difference.
    CentralDifference,
    /// Variable-order BDF (diffsol).
    Bdf,
    /// SDIRK (diffsol).
    Sdirk,
    /// Hilber–Hughes–Taylor α.
    HhtAlpha,
}

/// The declarations' defaults (an implicit integrator with bounded steps, no torque control,
/// no history, plane strain only).
const BASE: IntegratorTraits = IntegratorTraits {
    name: "",
    about: "",
    lumped_only: false,
    torque_control: false,
    history: false,
    rho_inf_min: 0.0,
    bounded_step: true,
    three_d: false,
};

impl IntegratorName {
    /// Every integrator, in registration order.
    pub const ALL: &'static [IntegratorName] = &[
        IntegratorName::GeneralizedAlpha,
        IntegratorName::CentralDifference,
        IntegratorName::Bdf,
        IntegratorName::Sdirk,
        IntegratorName::HhtAlpha,
    ];

    /// The scene keyword of every integrator, in registration order.
    pub const NAMES: &'static [&'static str] = &{
        let mut names = [""; IntegratorName::ALL.len()];
        let mut i = 0;
        while i < names.len() {
            names[i] = Self::ALL[i].traits().name;
            i += 1;
        }
        names
    };

    /// What the integrator declares.
    pub const fn traits(self) -> IntegratorTraits {
        match self {
            IntegratorName::GeneralizedAlpha => IntegratorTraits {
                name: "generalized_alpha",
                about: "Generalized-α (Chung–Hulbert) on the second-order system, with \
                        spectral radius at infinity `rho_inf` (1 = trapezoidal / Newmark average \
                        acceleration). Implicit.",
                torque_control: true,
                history: true,
                three_d: true,
                ..BASE
            },
            IntegratorName::CentralDifference => IntegratorTraits {
                name: "central_difference",
                about: "Explicit central difference with the lumped (HRZ) mass; the step is \
                        also bounded by a stable-step estimate.",
                lumped_only: true,
                history: true,
                three_d: true,
                ..BASE
            },
            IntegratorName::Bdf => IntegratorTraits {
                name: "bdf",
                about: "Variable-order BDF on the first-order form `y = (u, v)` (diffsol), \
                        with its own error control.",
                history: true,
                bounded_step: false,
                ..BASE
            },
            IntegratorName::Sdirk => IntegratorTraits {
                name: "sdirk",
                about: "SDIRK on the first-order form `y = (u, v)` (diffsol), with its own \
                        error control.",
                history: true,
                ..BASE
            },
            IntegratorName::HhtAlpha => IntegratorTraits {
                name: "hht_alpha",
                about: "Hilber–Hughes–Taylor α (the α-method of Abaqus/Standard), with \
                        spectral radius at infinity `rho_inf` in [0.5, 1]. Implicit.",
                torque_control: true,
                history: true,
                rho_inf_min: 0.5,
                three_d: true,
                ..BASE
            },
        }
    }

    /// The scene keyword.
    pub fn as_str(self) -> &'static str {
        self.traits().name
    }

    /// What it is ([`IntegratorTraits::about`]).
    pub fn about(self) -> &'static str {
        self.traits().about
    }

    /// See [`IntegratorTraits::lumped_only`].
    pub fn lumped_only(self) -> bool {
        self.traits().lumped_only
    }

    /// See [`IntegratorTraits::torque_control`].
    pub fn torque_control(self) -> bool {
        self.traits().torque_control
    }

    /// See [`IntegratorTraits::history`].
    pub fn carries_history(self) -> bool {
        self.traits().history
    }

    /// See [`IntegratorTraits::bounded_step`].
    pub fn bounded_step(self) -> bool {
        self.traits().bounded_step
    }

    /// See [`IntegratorTraits::rho_inf_min`].
    pub fn rho_inf_min(self) -> f64 {
        self.traits().rho_inf_min
    }

    /// See [`IntegratorTraits::three_d`].
    pub fn three_d(self) -> bool {
        self.traits().three_d
    }

    /// The scene keywords of the integrators for which `has` holds, quoted and joined by "or"
    /// (for messages: `"generalized_alpha" or "central_difference"`).
    pub fn quoted_with(has: impl Fn(IntegratorName) -> bool) -> String {
        let names: Vec<String> = Self::ALL
            .iter()
            .filter(|i| has(**i))
            .map(|i| format!("\"{i}\""))
            .collect();
        names.join(" or ")
    }
}

impl Default for IntegratorName {
    fn default() -> Self {
        IntegratorName::ALL[0]
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_is_listed_once_and_parses_back() {
        assert_eq!(IntegratorName::ALL.len(), IntegratorName::NAMES.len());
        for (i, n) in IntegratorName::ALL.iter().zip(IntegratorName::NAMES) {
            assert_eq!(i.as_str(), *n);
            assert_eq!(n.parse::<IntegratorName>(), Ok(*i));
            assert!(!i.about().is_empty());
            assert!((0.0..=1.0).contains(&i.rho_inf_min()));
        }
        let mut names = IntegratorName::NAMES.to_vec();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), IntegratorName::ALL.len());
        let e = "newmark".parse::<IntegratorName>().unwrap_err();
        assert!(
            e.contains("\"generalized_alpha\"") && e.contains("newmark"),
            "{e}"
        );
        assert_eq!(IntegratorName::default(), IntegratorName::GeneralizedAlpha);
    }
}
