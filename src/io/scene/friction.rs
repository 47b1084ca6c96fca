//! `[friction]`: the friction law `t_T = −μ(|w|) t_n φ_ε(w)` with slip velocity `w = ẋ1 − v0` (in
//! static, `w` is a slip per unit pseudo-time and `eps`, `v_s` are lengths).
//!
//! The section is `law` (a [`FrictionLawName`]) and the law's parameters. Which keys a law has,
//! what they mean, their units and bounds are declared by the law itself next to its physics
//! ([`crate::contact::FrictionLawSpec`]); this file holds the section as given (so that every
//! problem can be reported with its key), the generic checks that walk those declarations, and
//! the resolution into the physics law [`Friction`].

use super::issue::{issue, ordered_values, Issue};
use crate::contact::Friction;
use crate::params::LawKind;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Friction law (`[friction] law`): the keyword enum of the registered laws, `none` first.
pub use crate::contact::FrictionKind as FrictionLawName;

/// `[friction]` as given: the law and the parameter values by key. Which parameters are
/// required depends on `law`; [`FrictionSpec::params`] gives the physics law.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrictionSpec {
    pub law: FrictionLawName,
    /// Parameter values by key; only keys of some registered law (a key of another law than
    /// `law` is reported by the checks).
    pub values: BTreeMap<String, f64>,
}

impl FrictionSpec {
    /// A section with `law` and the given `(key, value)` pairs.
    pub fn new(law: FrictionLawName, values: &[(&str, f64)]) -> Self {
        Self {
            law,
            values: values.iter().map(|&(k, v)| (k.to_string(), v)).collect(),
        }
    }

    /// The value given for `key`.
    pub fn get(&self, key: &str) -> Option<f64> {
        self.values.get(key).copied()
    }

    /// Give `key` the value `value`.
    pub fn set(&mut self, key: &str, value: f64) {
        self.values.insert(key.to_string(), value);
    }

    /// Remove `key`.
    pub fn unset(&mut self, key: &str) {
        self.values.remove(key);
    }

    /// The physics law. `None` only if a parameter the law requires is missing, which cannot
    /// happen after validation.
    pub fn params(&self) -> Option<Friction> {
        self.law.build_from(|k| self.get(k)).ok()
    }

    /// Whether friction acts at all: false for law `none`, for a zero coefficient (`mu = 0`;
    /// `mu_s = mu_k = 0`; `c_t = 0`) and for an incomplete law.
    pub fn is_active(&self) -> bool {
        self.params().is_some_and(|f| f.is_active())
    }

    /// The keys of `[friction]` that belong to `law` (besides `law` itself).
    pub fn keys_of(law: FrictionLawName) -> Vec<&'static str> {
        law.params().iter().map(|p| p.key).collect()
    }

    /// The given keys: those of any law in the order of [`FrictionLawName::all_keys`], then
    /// any others.
    fn ordered(&self) -> Vec<(&str, f64)> {
        ordered_values(&self.values, &FrictionLawName::all_keys())
    }
}

impl Serialize for FrictionSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let given = self.ordered();
        let mut m = s.serialize_map(Some(1 + given.len()))?;
        m.serialize_entry("law", &self.law)?;
        for (k, v) in given {
            m.serialize_entry(k, &v)?;
        }
        m.end()
    }
}

impl<'de> Deserialize<'de> for FrictionSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        struct Given {
            #[serde(default)]
            law: FrictionLawName,
            #[serde(flatten)]
            values: BTreeMap<String, f64>,
        }
        let g = Given::deserialize(d)?;
        let known = FrictionLawName::all_keys();
        if let Some(key) = g.values.keys().find(|k| !known.contains(&k.as_str())) {
            return Err(serde::de::Error::custom(format!("unknown field `{key}`")));
        }
        Ok(FrictionSpec {
            law: g.law,
            values: g.values,
        })
    }
}

/// Whether the stick–slip oscillator can use friction law `law`: any law but `none` that
/// does not need a penetration.
pub fn stick_slip_law(law: FrictionLawName) -> bool {
    crate::contact::stick_slip::supports(law)
}

/// The keywords of the friction laws the stick–slip oscillator can use, in registration order.
pub fn stick_slip_laws() -> Vec<&'static str> {
    crate::contact::stick_slip::supported_laws()
}

/// The checks of `[friction]`, from the law's declared parameters: keys of another law, missing
/// parameters, values out of their bounds, then the law's own checks between parameters.
pub(super) fn validate_friction(f: &FrictionSpec, out: &mut Vec<Issue>) {
    let law = f.law;
    let allowed = FrictionSpec::keys_of(law);
    for (key, _) in f.ordered() {
        if !allowed.contains(&key) {
            let keys = if allowed.is_empty() {
                format!("law \"{law}\" takes no other key")
            } else {
                format!("its keys are law, {}", allowed.join(", "))
            };
            out.push(issue(
                format!("friction.{key}"),
                format!("`{key}` is not a parameter of friction law \"{law}\" ({keys})"),
            ));
        }
    }
    for p in law.params() {
        match f.get(p.key) {
            None => out.push(issue(
                format!("friction.{}", p.key),
                format!("required for friction law \"{law}\" ({})", p.what),
            )),
            Some(x) if !p.bound.admits(x) => out.push(issue(
                format!("friction.{}", p.key),
                format!("{} must be {}, got {x}", p.what, p.bound),
            )),
            Some(_) => {}
        }
    }
    for (key, message) in law.cross_check(&|k| f.get(k)) {
        out.push(issue(format!("friction.{key}"), message));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::laws::{CoulombLinear, OdenMartins};
    use crate::io::scene::tests::*;

    #[test]
    fn friction_params_and_is_active() {
        let mut f = FrictionSpec::new(
            FrictionLawName::CoulombLinear,
            &[("mu", 0.0), ("eps", 1e-3)],
        );
        assert_eq!(
            f.params(),
            Some(Friction::CoulombLinear(CoulombLinear::new(0.0, 1e-3)))
        );
        assert!(!f.is_active(), "zero coefficient");
        f.set("mu", 0.2);
        assert!(f.is_active());
        f.unset("eps");
        assert_eq!(f.params(), None);
        assert!(!f.is_active(), "incomplete");
        let om = FrictionSpec::new(
            FrictionLawName::OdenMartins,
            &[("c_t", 5.0), ("m_t", 1.5), ("eps", 1e-3)],
        );
        assert_eq!(
            om.params(),
            Some(Friction::OdenMartins(OdenMartins::new(5.0, 1.5, 1e-3)))
        );
        assert!(om.is_active());
        let rd = FrictionSpec::new(
            FrictionLawName::RateDependent,
            &[("mu_s", 0.0), ("mu_k", 0.0), ("v_s", 1.0), ("eps", 1e-3)],
        );
        assert!(!rd.is_active());
        assert_eq!(FrictionSpec::keys_of(FrictionLawName::None), &[] as &[&str]);
        assert_eq!(
            FrictionSpec::keys_of(FrictionLawName::RateDependent),
            &["mu_s", "mu_k", "v_s", "eps"]
        );
    }

    #[test]
    fn negative_mu_and_non_positive_eps_rejected() {
        let text = replace_line(FRICTION, "mu =", "mu = -0.1");
        let e = errors(&text);
        assert_only(&e, "friction.mu", Some(line_of(&text, "mu =")));
        assert!(e.0[0].message.contains(">= 0"), "{e}");
        assert!(load(&replace_line(FRICTION, "mu =", "mu = 0.0")).is_ok());

        for bad in ["eps = 0.0", "eps = -0.01"] {
            let text = replace_line(FRICTION, "eps", bad);
            let e = errors(&text);
            assert_only(&e, "friction.eps", Some(line_of(&text, "eps")));
            assert!(e.0[0].message.contains("> 0"), "{e}");
        }
        let text = replace_line(STICK_SLIP, "eps", "eps = 0");
        let e = errors(&text);
        assert_only(&e, "friction.eps", Some(line_of(&text, "eps")));
        let text = replace_line(STICK_SLIP, "mu_s", "mu_s = -0.6");
        let e = errors(&text);
        assert_only(&e, "friction.mu_s", Some(line_of(&text, "mu_s")));
        let text = replace_line(STICK_SLIP, "v_s", "v_s = 0.0");
        let e = errors(&text);
        assert_only(&e, "friction.v_s", Some(line_of(&text, "v_s")));
    }

    #[test]
    fn kinetic_above_static_rejected() {
        let text = replace_line(STICK_SLIP, "mu_k", "mu_k = 0.7");
        let e = errors(&text);
        assert_only(&e, "friction.mu_k", Some(line_of(&text, "mu_k")));
        assert!(e.0[0].message.contains("must not exceed"), "{e}");
        assert!(load(&replace_line(STICK_SLIP, "mu_k", "mu_k = 0.6")).is_ok());
    }

    #[test]
    fn oden_martins_keys_checked() {
        let text = FRICTIONLESS.replace(
            "law = \"none\"",
            "law = \"oden_martins\"\nc_t = 6.0e4\nm_t = 0.5\neps = 0.01",
        );
        let e = errors(&text);
        assert_only(&e, "friction.m_t", Some(line_of(&text, "m_t")));
        let s = load(&replace_line(&text, "m_t", "m_t = 1.0")).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            s.friction.params(),
            Some(Friction::OdenMartins(OdenMartins::new(6.0e4, 1.0, 0.01)))
        );
        // Missing keys of the law: reported at the [friction] header.
        let text = FRICTIONLESS.replace("law = \"none\"", "law = \"oden_martins\"");
        let e = errors(&text);
        assert_eq!(e.0.len(), 3, "{e}");
        for key in ["friction.c_t", "friction.m_t", "friction.eps"] {
            let err = e.find(key).unwrap_or_else(|| panic!("{e}"));
            assert_eq!(err.line, Some(line_of(&text, "[friction]")));
            assert!(err.message.contains("required for friction law"), "{err}");
        }
    }

    #[test]
    fn friction_key_of_another_law_rejected() {
        let text = replace_line(FRICTION, "eps", "eps = 0.01\nmu_s = 0.5");
        let e = errors(&text);
        assert_only(&e, "friction.mu_s", Some(line_of(&text, "mu_s")));
        assert!(e.0[0].message.contains("not a parameter"), "{e}");
        assert!(e.0[0].message.contains("coulomb_tanh"), "{e}");
        assert!(e.0[0].message.contains("law, mu, eps"), "{e}");

        let text = replace_line(STICK_SLIP, "v_s", "v_s = 0.01\nmu = 0.5");
        let e = errors(&text);
        assert_only(&e, "friction.mu", Some(line_of(&text, "mu = 0.5")));

        let text = FRICTIONLESS.replace("law = \"none\"", "law = \"none\"\nmu = 0.3");
        let e = errors(&text);
        assert_only(&e, "friction.mu", Some(line_of(&text, "mu =")));
        assert!(e.0[0].message.contains("takes no other key"), "{e}");
    }

    /// The elastic-slip law is accepted in the steady mode and rejected, naming the law and the
    /// mode, elsewhere (static indentation, the stick–slip oscillator).
    #[test]
    fn elastic_slip_law_only_in_steady() {
        let elastic = "law = \"coulomb_elastic\"\nk_t = 1.0e5";
        let carter = include_str!("../../../scenarios/carter_tractive_rolling.toml");
        let steady = replace_line(&replace_line(carter, "law", elastic), "eps", "");
        let s = load(&steady).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            s.friction.params(),
            Some(Friction::CoulombElastic(
                crate::contact::laws::CoulombElastic::new(0.5, 1.0e5)
            ))
        );
        let text = replace_line(&replace_line(FRICTION, "law", elastic), "eps", "");
        let e = errors(&text);
        let err = e.find("friction.law").unwrap_or_else(|| panic!("{e}"));
        assert!(err.message.contains("coulomb_elastic"), "{err}");
        assert!(err.message.contains("\"steady\" only"), "{err}");
        let text = replace_line(STICK_SLIP, "law", "law = \"coulomb_elastic\"");
        let e = errors(&text);
        assert!(e.find("friction.law").is_some(), "{e}");
    }

    #[test]
    fn invalid_friction_law_reported_once() {
        // The keys of an unknown law are not checked against the default law.
        let text = replace_line(FRICTION, "law", "law = \"coulomb\"");
        let e = errors(&text);
        assert_only(&e, "friction.law", Some(line_of(&text, "law")));
        assert!(e.0[0].message.contains("coulomb_tanh"), "{e}");
        let text = replace_line(STICK_SLIP, "law", "law = 3");
        let e = errors(&text);
        assert_only(&e, "friction.law", Some(line_of(&text, "law")));
    }
}
