//! `[friction]`: the friction law `t_T = −μ(|w|) t_n φ_ε(w)` with slip velocity `w = ẋ1 − v0` (in
//! static, `w` is a slip per unit pseudo-time and `eps`, `v_s` are lengths).

use super::issue::{issue, Issue};
use serde::{Deserialize, Serialize};

keyword_enum! {
    /// Friction law (`[friction] law`).
    #[derive(Default)]
    FrictionLawName, "friction law" {
        #[default]
        /// No friction (frictionless contact).
        None => "none",
        /// Coulomb, `t_T = −μ t_n tanh(w/ε)`.
        CoulombTanh => "coulomb_tanh",
        /// Coulomb, `t_T = −μ t_n clamp(w/ε, −1, 1)`.
        CoulombLinear => "coulomb_linear",
        /// `μ(|w|) = μ_k + (μ_s − μ_k) exp(−|w|/v_s)`, `t_T = −μ(|w|) t_n tanh(w/ε)`.
        RateDependent => "rate_dependent",
        /// Oden–Martins normal-compliance friction, `t_T = −c_t δ^m_t tanh(w/ε)`.
        OdenMartins => "oden_martins",
    }
}

/// `[friction]`. Which of the optional parameters are required depends on `law`;
/// [`FrictionSpec::params`] gives them as one enum.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrictionSpec {
    #[serde(default)]
    pub law: FrictionLawName,
    /// Coulomb coefficient (coulomb_tanh, coulomb_linear), >= 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu: Option<f64>,
    /// Regularisation of the slip velocity (velocity; a slip length in `static`), > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eps: Option<f64>,
    /// Static coefficient (rate_dependent), >= 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu_s: Option<f64>,
    /// Kinetic coefficient (rate_dependent), in [0, mu_s].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu_k: Option<f64>,
    /// Decay velocity of μ from mu_s to mu_k (rate_dependent), > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub v_s: Option<f64>,
    /// Oden–Martins tangential compliance coefficient (stress/length^m_t), >= 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub c_t: Option<f64>,
    /// Oden–Martins tangential compliance exponent, >= 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub m_t: Option<f64>,
}

/// Resolved friction parameters, one variant per law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FrictionParams {
    None,
    CoulombTanh {
        mu: f64,
        eps: f64,
    },
    CoulombLinear {
        mu: f64,
        eps: f64,
    },
    RateDependent {
        mu_s: f64,
        mu_k: f64,
        v_s: f64,
        eps: f64,
    },
    OdenMartins {
        c_t: f64,
        m_t: f64,
        eps: f64,
    },
}

impl FrictionSpec {
    /// The parameters of the chosen law. `None` only if a parameter the law requires is
    /// missing, which cannot happen after validation.
    pub fn params(&self) -> Option<FrictionParams> {
        match self.law {
            FrictionLawName::None => Some(FrictionParams::None),
            FrictionLawName::CoulombTanh => Some(FrictionParams::CoulombTanh {
                mu: self.mu?,
                eps: self.eps?,
            }),
            FrictionLawName::CoulombLinear => Some(FrictionParams::CoulombLinear {
                mu: self.mu?,
                eps: self.eps?,
            }),
            FrictionLawName::RateDependent => Some(FrictionParams::RateDependent {
                mu_s: self.mu_s?,
                mu_k: self.mu_k?,
                v_s: self.v_s?,
                eps: self.eps?,
            }),
            FrictionLawName::OdenMartins => Some(FrictionParams::OdenMartins {
                c_t: self.c_t?,
                m_t: self.m_t?,
                eps: self.eps?,
            }),
        }
    }

    /// Whether friction acts at all: false for law `none`, for a zero coefficient (`mu = 0`;
    /// `mu_s = mu_k = 0`; `c_t = 0`) and for an incomplete law.
    pub fn is_active(&self) -> bool {
        match self.params() {
            None | Some(FrictionParams::None) => false,
            Some(FrictionParams::CoulombTanh { mu, .. })
            | Some(FrictionParams::CoulombLinear { mu, .. }) => mu > 0.0,
            Some(FrictionParams::RateDependent { mu_s, mu_k, .. }) => mu_s > 0.0 || mu_k > 0.0,
            Some(FrictionParams::OdenMartins { c_t, .. }) => c_t > 0.0,
        }
    }

    /// The keys of `[friction]` that belong to `law` (besides `law` itself).
    pub fn keys_of(law: FrictionLawName) -> &'static [&'static str] {
        match law {
            FrictionLawName::None => &[],
            FrictionLawName::CoulombTanh | FrictionLawName::CoulombLinear => &["mu", "eps"],
            FrictionLawName::RateDependent => &["mu_s", "mu_k", "v_s", "eps"],
            FrictionLawName::OdenMartins => &["c_t", "m_t", "eps"],
        }
    }
}

pub(super) fn validate_friction(f: &FrictionSpec, out: &mut Vec<Issue>) {
    let law = f.law;
    let given: [(&str, Option<f64>); 7] = [
        ("mu", f.mu),
        ("eps", f.eps),
        ("mu_s", f.mu_s),
        ("mu_k", f.mu_k),
        ("v_s", f.v_s),
        ("c_t", f.c_t),
        ("m_t", f.m_t),
    ];
    let allowed = FrictionSpec::keys_of(law);
    for (key, value) in given {
        if value.is_some() && !allowed.contains(&key) {
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
    // (key, value, what, lower bound, whether the bound is strict)
    let need = |key: &str,
                v: Option<f64>,
                what: &str,
                lo: f64,
                strict: bool,
                out: &mut Vec<Issue>| {
        match v {
            None => out.push(issue(
                format!("friction.{key}"),
                format!("required for friction law \"{law}\" ({what})"),
            )),
            Some(x) if !(x.is_finite() && if strict { x > lo } else { x >= lo }) => {
                let op = if strict { ">" } else { ">=" };
                out.push(issue(
                    format!("friction.{key}"),
                    format!("{what} must be {op} {lo}, got {x}"),
                ));
            }
            Some(_) => {}
        }
    };
    const EPS: &str = "slip-velocity regularisation ε";
    match law {
        FrictionLawName::None => {}
        FrictionLawName::CoulombTanh | FrictionLawName::CoulombLinear => {
            need("mu", f.mu, "friction coefficient μ", 0.0, false, out);
            need("eps", f.eps, EPS, 0.0, true, out);
        }
        FrictionLawName::RateDependent => {
            need(
                "mu_s",
                f.mu_s,
                "static friction coefficient μ_s",
                0.0,
                false,
                out,
            );
            need(
                "mu_k",
                f.mu_k,
                "kinetic friction coefficient μ_k",
                0.0,
                false,
                out,
            );
            need("v_s", f.v_s, "decay velocity v_s", 0.0, true, out);
            need("eps", f.eps, EPS, 0.0, true, out);
            if let (Some(mu_s), Some(mu_k)) = (f.mu_s, f.mu_k) {
                if mu_s >= 0.0 && mu_k >= 0.0 && mu_k > mu_s {
                    out.push(issue(
                        "friction.mu_k",
                        format!(
                            "kinetic coefficient μ_k = {mu_k} must not exceed the static \
                             coefficient μ_s = {mu_s}"
                        ),
                    ));
                }
            }
        }
        FrictionLawName::OdenMartins => {
            need(
                "c_t",
                f.c_t,
                "tangential compliance coefficient c_t",
                0.0,
                false,
                out,
            );
            need(
                "m_t",
                f.m_t,
                "tangential compliance exponent m_t",
                1.0,
                false,
                out,
            );
            need("eps", f.eps, EPS, 0.0, true, out);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::scene::tests::*;

    #[test]
    fn friction_params_and_is_active() {
        let mut f = FrictionSpec {
            law: FrictionLawName::CoulombLinear,
            mu: Some(0.0),
            eps: Some(1e-3),
            ..FrictionSpec::default()
        };
        assert_eq!(
            f.params(),
            Some(FrictionParams::CoulombLinear { mu: 0.0, eps: 1e-3 })
        );
        assert!(!f.is_active(), "zero coefficient");
        f.mu = Some(0.2);
        assert!(f.is_active());
        f.eps = None;
        assert_eq!(f.params(), None);
        assert!(!f.is_active(), "incomplete");
        let om = FrictionSpec {
            law: FrictionLawName::OdenMartins,
            c_t: Some(5.0),
            m_t: Some(1.5),
            eps: Some(1e-3),
            ..FrictionSpec::default()
        };
        assert_eq!(
            om.params(),
            Some(FrictionParams::OdenMartins {
                c_t: 5.0,
                m_t: 1.5,
                eps: 1e-3
            })
        );
        assert!(om.is_active());
        let rd = FrictionSpec {
            law: FrictionLawName::RateDependent,
            mu_s: Some(0.0),
            mu_k: Some(0.0),
            v_s: Some(1.0),
            eps: Some(1e-3),
            ..FrictionSpec::default()
        };
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
            Some(FrictionParams::OdenMartins {
                c_t: 6.0e4,
                m_t: 1.0,
                eps: 0.01
            })
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
