//! `[friction]`: the friction law `t_T = −μ(|w|) t_n φ_ε(w)` with slip velocity `w = ẋ1 − v0` (in
//! static, `w` is a slip per unit pseudo-time and `eps`, `v_s` are lengths).

use super::*;

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
