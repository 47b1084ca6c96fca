//! Interface laws for the contact of the body with the rigid road: normal compliance and
//! (regularised, non-classical) friction, each with its consistent derivatives.
//!
//! These are pure pointwise functions. They are evaluated at the quadrature points of the contact
//! boundary Γ_C by the assembly kernels and, for the stick–slip oscillator of
//! [`super::stick_slip`], on a single degree of freedom.
//!
//! # Sign conventions (fixed by the project)
//!
//! - Penetration δ = (−H − x2)_+ ≥ 0 (road surface x2 = −H), δ̇ its rate (δ̇ = −ẋ2 when in contact).
//! - Slip velocity of the body relative to the road: w = ẋ1 − v0 (the paper's w_T = −w).
//! - Normal traction on the body t_n ≥ 0 pushes it in +x2 (away from the road).
//! - Tangential traction on the body t_T opposes slip: t_T·w ≤ 0.
//!
//! # Units
//!
//! Tractions are force per unit (reference) length of Γ_C in plane strain, in whatever consistent
//! units the scene uses. δ is a length and w, δ̇ are velocities; so c_n has units
//! traction/length^{m_n}, b_n traction·time/length^{1+l_n}, ε (the friction regularisation) and
//! v_s are velocities, μ, μ_s, μ_k are dimensionless and c_T has units traction/length^{m_T}.
//!
//! # Normal compliance (paper Fig. 5)
//!
//! t_n = c_n δ^{m_n} + b_n δ^{l_n} δ̇   for δ > 0,  clamped at t_n ≥ 0 (no adhesion);
//! t_n = 0 for δ ≤ 0. With m_n = 1 and c_n = 1/ε this is the exterior penalty. Where the clamp is
//! active (raw t_n ≤ 0, only possible with damping and a receding body δ̇ < 0), the traction and
//! both derivatives are zero. The clamp is max(0, ·) by default ([`Clamp::Hard`], the project's
//! convention); [`Clamp::Smooth`] replaces it by a C¹ cubic ramp of a given width (scene key
//! `contact.clamp = "smooth"`, `contact.clamp_width`), to study the kink it puts inside a
//! damped contact patch.
//!
//! # Friction (paper Fig. 7 and §4)
//!
//! t_T = −μ(|w|) t_n φ_ε(w), with the regularised sign φ_ε:
//!
//! | law               | μ(|w|)                                   | φ_ε(w)                   |
//! |-------------------|------------------------------------------|--------------------------|
//! | [`CoulombTanh`]   | μ                                        | tanh(w/ε)                |
//! | [`CoulombLinear`] | μ                                        | clamp(w/ε, −1, 1)        |
//! | [`RateDependent`] | μ_k + (μ_s − μ_k) exp(−|w|/v_s)          | tanh(w/ε)                |
//! | [`OdenMartins`]   | (compliance type) t_T = −c_T δ^{m_T} φ_ε | tanh(w/ε)                |
//!
//! [`CoulombElastic`] (steady mode only) is not a law of the slip velocity: t_T = −k_T g bounded
//! by μ t_n, with g the elastic part of the tangential relative displacement, marched along the
//! streamlines by [`super::steady_elastic`].
//!
//! The Oden–Martins law does not use t_n: the tangential traction is a power of the penetration,
//! as the normal one is. With m_T = m_n and c_T = μ c_n (and no normal damping) it reduces to the
//! regularised Coulomb law.
//!
//! The friction laws take t_n as an argument and use max(t_n, 0) (a negative normal traction
//! would otherwise make friction drive the slip); d_tn is zero where t_n < 0.
//!
//! # Scene description and registration
//!
//! Each friction law declares, next to its physics, how a scene file gives it
//! ([`FrictionLawSpec`]): its `law` keyword, its parameters ([`ParamSpec`]: key, meaning, unit,
//! bound), how to build it from their values and any check between parameters. The one list in
//! `friction_laws!` builds from these entries both the [`Friction`] enum with its dispatch and
//! the keyword enum [`FrictionKind`]; the scene's `[friction]` keys, reference, range checks and
//! messages are made from the declarations. Adding a law is its struct with its
//! [`FrictionLaw`] and [`FrictionLawSpec`] impls, plus its name in that list.
//!
//! [`RateDependent`]: |w| is not differentiable at w = 0, but μ(|w|) tanh(w/ε) is C¹ there:
//! sign(w) tanh(w/ε) = tanh(|w|/ε), so
//! d/dw [μ(|w|) tanh(w/ε)] = μ'(|w|) tanh(|w|/ε) + μ(|w|) sech²(w/ε)/ε,
//! which is continuous and even in w; that form is what [`RateDependent::eval`] uses.

pub use crate::params::{Bound, LawKind, ParamSpec};
use serde::{Deserialize, Serialize};

/// Error in the parameters of an interface law (the offending parameter is named).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LawError {
    /// A parameter is out of its admissible range.
    #[error("interface law parameter `{name}` = {value} is invalid: {reason}")]
    InvalidParameter {
        /// Parameter name as in the scene file (`c_n`, `mu`, `eps`, ...).
        name: &'static str,
        /// The offending value.
        value: f64,
        /// What is required.
        reason: String,
    },
}

fn check(name: &'static str, value: f64, ok: bool, reason: &str) -> Result<(), LawError> {
    if ok && value.is_finite() {
        Ok(())
    } else {
        Err(LawError::InvalidParameter {
            name,
            value,
            reason: reason.to_string(),
        })
    }
}

/// δ^m and d(δ^m)/dδ = m δ^{m−1} for δ > 0, with m = 1 and m = 0 handled exactly
/// (so that no 0·∞ or powf rounding appears in the common penalty case).
#[inline]
fn pow_with_derivative(delta: f64, m: f64) -> (f64, f64) {
    if m == 1.0 {
        (delta, 1.0)
    } else if m == 0.0 {
        (1.0, 0.0)
    } else if m == 2.0 {
        (delta * delta, 2.0 * delta)
    } else {
        let p = delta.powf(m - 1.0);
        (p * delta, m * p)
    }
}

/// tanh(x) and its derivative sech²(x) = 1/cosh²(x) (accurate also where tanh(x) ≈ ±1).
#[inline]
fn tanh_with_derivative(x: f64) -> (f64, f64) {
    let c = x.cosh();
    (x.tanh(), 1.0 / (c * c))
}

/// Value of the normal compliance law and its partial derivatives.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NormalValue {
    /// Normal traction on the body t_n ≥ 0 (pushes it in +x2).
    pub t: f64,
    /// ∂t_n/∂δ.
    pub d_delta: f64,
    /// ∂t_n/∂δ̇.
    pub d_rate: f64,
}

/// How the normal traction is kept non-negative (no adhesion): t_n = clamp(r) of the raw value
/// r = c_n δ^{m_n} + b_n δ^{l_n} δ̇ (δ > 0).
///
/// | variant  | clamp(r)                                                  | smoothness |
/// |----------|-----------------------------------------------------------|------------|
/// | `Hard`   | max(0, r)                                                 | C⁰ (kink at r = 0) |
/// | `Smooth` | 0 for r ≤ 0; r² (2w − r) / w² for 0 < r < w; r for r ≥ w  | C¹         |
///
/// The smooth ramp (width w, a traction) is the cubic that matches 0 and the raw law with
/// their slopes at both ends of [0, w]: it is monotone, 0 ≤ clamp(r) ≤ r, and differs from the
/// hard clamp only where 0 < r < w (by at most 4w/27, at r = w/3). Unlike a softplus
/// w ln(1 + e^{r/w}) it adds no traction where r ≤ 0 (no spurious push where the raw law is
/// negative, and no new jump at δ = 0), and it leaves the law exact once r ≥ w. Note that for
/// m_n = 1 without damping (r = c_n δ) it also rounds the kink of the penalty at δ = 0 over
/// δ < w / c_n. The project's default is `Hard`; `Smooth` is an option to study
/// the effect of the kink.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Clamp {
    /// t_n = max(0, r).
    #[default]
    Hard,
    /// The C¹ cubic ramp of width `width` (traction units, > 0).
    Smooth { width: f64 },
}

impl Clamp {
    /// clamp(r) and d clamp / dr.
    #[inline]
    pub fn apply(&self, r: f64) -> (f64, f64) {
        if r <= 0.0 {
            return (0.0, 0.0);
        }
        match *self {
            Clamp::Hard => (r, 1.0),
            Clamp::Smooth { width: w } => {
                if r >= w {
                    (r, 1.0)
                } else {
                    let w2 = w * w;
                    (r * r * (2.0 * w - r) / w2, r * (4.0 * w - 3.0 * r) / w2)
                }
            }
        }
    }
}

/// Normal compliance with optional damping: t_n = c_n δ^{m_n} + b_n δ^{l_n} δ̇, clamped at 0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NormalCompliance {
    /// Stiffness coefficient c_n > 0.
    pub c_n: f64,
    /// Stiffness exponent m_n ≥ 1 (1: linear penalty).
    pub m_n: f64,
    /// Damping coefficient b_n ≥ 0 (0: no damping).
    pub b_n: f64,
    /// Damping exponent l_n ≥ 0.
    pub l_n: f64,
    /// The no-adhesion clamp (hard by default).
    #[serde(default)]
    pub clamp: Clamp,
}

impl NormalCompliance {
    /// A law with the given parameters and the hard clamp.
    pub fn new(c_n: f64, m_n: f64, b_n: f64, l_n: f64) -> Self {
        Self {
            c_n,
            m_n,
            b_n,
            l_n,
            clamp: Clamp::Hard,
        }
    }

    /// The same law with another clamp.
    pub fn with_clamp(mut self, clamp: Clamp) -> Self {
        self.clamp = clamp;
        self
    }

    /// The exterior penalty t_n = c_n δ (m_n = 1, no damping).
    pub fn penalty(c_n: f64) -> Self {
        Self::new(c_n, 1.0, 0.0, 0.0)
    }

    /// Whether the rate term is present (then t_n depends on δ̇ and the tangent is unsymmetric).
    pub fn has_damping(&self) -> bool {
        self.b_n != 0.0
    }

    /// Check the parameters: c_n > 0, m_n ≥ 1, b_n ≥ 0, l_n ≥ 0, all finite.
    ///
    /// m_n ≥ 1 keeps ∂t_n/∂δ bounded at δ → 0⁺ (Newton needs that); l_n ≥ 0 likewise for ∂t_n/∂δ̇.
    pub fn validate(&self) -> Result<(), LawError> {
        check("c_n", self.c_n, self.c_n > 0.0, "must be > 0")?;
        check("m_n", self.m_n, self.m_n >= 1.0, "must be >= 1")?;
        check("b_n", self.b_n, self.b_n >= 0.0, "must be >= 0")?;
        check("l_n", self.l_n, self.l_n >= 0.0, "must be >= 0")?;
        match self.clamp {
            Clamp::Hard => Ok(()),
            Clamp::Smooth { width } => check("clamp_width", width, width > 0.0, "must be > 0"),
        }
    }

    /// Normal traction and its derivatives at penetration `delta` (δ) and rate `delta_dot` (δ̇).
    ///
    /// Zero for δ ≤ 0 and wherever the raw value c_n δ^{m_n} + b_n δ^{l_n} δ̇ is ≤ 0 (clamp);
    /// with [`Clamp::Smooth`] the raw value is passed through the C¹ ramp.
    #[inline]
    pub fn eval(&self, delta: f64, delta_dot: f64) -> NormalValue {
        if delta <= 0.0 {
            return NormalValue::default();
        }
        let (pm, dpm) = pow_with_derivative(delta, self.m_n);
        let mut t = self.c_n * pm;
        let mut d_delta = self.c_n * dpm;
        let mut d_rate = 0.0;
        if self.b_n != 0.0 {
            let (pl, dpl) = pow_with_derivative(delta, self.l_n);
            t += self.b_n * pl * delta_dot;
            d_delta += self.b_n * dpl * delta_dot;
            d_rate = self.b_n * pl;
        }
        if t <= 0.0 {
            return NormalValue::default();
        }
        if let Clamp::Smooth { .. } = self.clamp {
            let (c, dc) = self.clamp.apply(t);
            return NormalValue {
                t: c,
                d_delta: dc * d_delta,
                d_rate: dc * d_rate,
            };
        }
        NormalValue { t, d_delta, d_rate }
    }
}

/// Value of a friction law and its partial derivatives.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FrictionValue {
    /// Tangential traction on the body t_T (opposes the slip w).
    pub t: f64,
    /// ∂t_T/∂w.
    pub d_w: f64,
    /// ∂t_T/∂t_n.
    pub d_tn: f64,
    /// ∂t_T/∂δ (non-zero only for compliance-type laws).
    pub d_delta: f64,
}

/// A friction law: tangential traction from slip w, normal traction t_n and penetration δ.
pub trait FrictionLaw: Send + Sync {
    /// Traction t_T on the body and its derivatives at slip `w`, normal traction `t_n`,
    /// penetration `delta`.
    fn eval(&self, w: f64, t_n: f64, delta: f64) -> FrictionValue;
}

/// The regularisation velocity ε, a parameter of every law.
const EPS: ParamSpec = ParamSpec {
    key: "eps",
    what: "slip-velocity regularisation ε",
    unit: "L/T (static: L)",
    bound: Bound::Above(0.0),
    note: "a slip length in static",
};

/// The Coulomb coefficient μ of both Coulomb laws.
const MU: ParamSpec = ParamSpec {
    key: "mu",
    what: "friction coefficient μ",
    unit: "–",
    bound: Bound::AtLeast(0.0),
    note: "",
};

/// A friction law with its scene description: the keyword, the parameters, and how to build the
/// law from their values. Registering the type in `friction_laws!` adds it to [`Friction`] and to
/// the scene's `[friction] law` keywords, keys, checks and reference.
pub trait FrictionLawSpec: FrictionLaw + Copy {
    /// Keyword of `[friction] law` (snake_case).
    const NAME: &'static str;
    /// Parameters, in the order of [`Self::from_values`] and [`Self::values`].
    const PARAMS: &'static [ParamSpec];
    /// Whether the traction is a function of the penetration δ rather than of t_n, so that the
    /// law cannot act on the stick–slip oscillator (which has no δ).
    const NEEDS_PENETRATION: bool = false;
    /// Whether only the steady mode can supply the law's argument (the elastic slip of
    /// [`CoulombElastic`]), so that the scene rejects the law in the other modes.
    const STEADY_ONLY: bool = false;

    /// The law from its parameter values in the order of [`Self::PARAMS`] (not range-checked).
    fn from_values(v: &[f64]) -> Self;

    /// The parameter values in the order of [`Self::PARAMS`].
    fn values(&self) -> Vec<f64>;

    /// Whether the law can produce a non-zero traction.
    fn is_active(&self) -> bool;

    /// The friction coefficient at large slip, where the law has one.
    fn kinetic_coefficient(&self) -> Option<f64> {
        None
    }

    /// Checks between parameters beyond their own bounds, on the values a scene gives (any may
    /// be missing): `(key, message)` for each violation.
    fn cross_check(_given: &dyn Fn(&str) -> Option<f64>) -> Vec<(&'static str, String)> {
        Vec::new()
    }
}

/// Regularised Coulomb friction t_T = −μ t_n tanh(w/ε).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CoulombTanh {
    /// Friction coefficient μ ≥ 0.
    pub mu: f64,
    /// Regularisation velocity ε > 0.
    pub eps: f64,
}

impl CoulombTanh {
    /// A law with coefficient `mu` and regularisation velocity `eps`.
    pub fn new(mu: f64, eps: f64) -> Self {
        Self { mu, eps }
    }
}

impl FrictionLawSpec for CoulombTanh {
    const NAME: &'static str = "coulomb_tanh";
    const PARAMS: &'static [ParamSpec] = &[MU, EPS];

    fn from_values(v: &[f64]) -> Self {
        Self::new(v[0], v[1])
    }

    fn values(&self) -> Vec<f64> {
        vec![self.mu, self.eps]
    }

    fn is_active(&self) -> bool {
        self.mu != 0.0
    }

    fn kinetic_coefficient(&self) -> Option<f64> {
        Some(self.mu)
    }
}

impl FrictionLaw for CoulombTanh {
    #[inline]
    fn eval(&self, w: f64, t_n: f64, _delta: f64) -> FrictionValue {
        if t_n <= 0.0 {
            return FrictionValue::default();
        }
        let (phi, dphi) = tanh_with_derivative(w / self.eps);
        FrictionValue {
            t: -self.mu * t_n * phi,
            d_w: -self.mu * t_n * dphi / self.eps,
            d_tn: -self.mu * phi,
            d_delta: 0.0,
        }
    }
}

/// Regularised Coulomb friction with the piecewise-linear sign t_T = −μ t_n clamp(w/ε, −1, 1).
///
/// Not differentiable at |w| = ε; there the derivative of the outer (sliding) branch, zero, is
/// returned.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CoulombLinear {
    /// Friction coefficient μ ≥ 0.
    pub mu: f64,
    /// Regularisation velocity ε > 0.
    pub eps: f64,
}

impl CoulombLinear {
    /// A law with coefficient `mu` and regularisation velocity `eps`.
    pub fn new(mu: f64, eps: f64) -> Self {
        Self { mu, eps }
    }
}

impl FrictionLawSpec for CoulombLinear {
    const NAME: &'static str = "coulomb_linear";
    const PARAMS: &'static [ParamSpec] = &[MU, EPS];

    fn from_values(v: &[f64]) -> Self {
        Self::new(v[0], v[1])
    }

    fn values(&self) -> Vec<f64> {
        vec![self.mu, self.eps]
    }

    fn is_active(&self) -> bool {
        self.mu != 0.0
    }

    fn kinetic_coefficient(&self) -> Option<f64> {
        Some(self.mu)
    }
}

impl FrictionLaw for CoulombLinear {
    #[inline]
    fn eval(&self, w: f64, t_n: f64, _delta: f64) -> FrictionValue {
        if t_n <= 0.0 {
            return FrictionValue::default();
        }
        let s = w / self.eps;
        let (phi, dphi) = if s.abs() < 1.0 {
            (s, 1.0 / self.eps)
        } else {
            (s.signum(), 0.0)
        };
        FrictionValue {
            t: -self.mu * t_n * phi,
            d_w: -self.mu * t_n * dphi,
            d_tn: -self.mu * phi,
            d_delta: 0.0,
        }
    }
}

/// Elastic-slip Coulomb friction of the steady mode: a tangential penalty k_T on the elastic
/// part of the tangential relative displacement g (a length, not a velocity), bounded by the
/// Coulomb cone,
///
/// ```text
/// t_T = −k_T g   where k_T |g| ≤ μ t_n (stick),    t_T = −μ t_n sign(g) otherwise (slip).
/// ```
///
/// The steady mode gives g at every contact point by a return mapping marched along the
/// streamline from where the material enters the patch ([`super::steady_elastic`]); the
/// pointwise [`FrictionLaw::eval`] here is that return mapping for a given trial g (its first
/// argument), the building block of the march. No velocity regularisation: as k_T → ∞ the law
/// is exact Coulomb. Only the steady mode supplies g (the scene accepts the law only there).
///
/// Not differentiable at k_T |g| = μ t_n; there the derivative of the slip branch is returned.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CoulombElastic {
    /// Friction coefficient μ ≥ 0.
    pub mu: f64,
    /// Tangential stiffness k_T > 0 (traction per length).
    pub k_t: f64,
}

impl CoulombElastic {
    /// A law with coefficient `mu` and tangential stiffness `k_t`.
    pub fn new(mu: f64, k_t: f64) -> Self {
        Self { mu, k_t }
    }
}

/// The tangential stiffness k_T of the elastic-slip law.
const K_T: ParamSpec = ParamSpec {
    key: "k_t",
    what: "tangential stiffness k_T of the elastic slip",
    unit: "F/L²",
    bound: Bound::Above(0.0),
    note: "steady mode only",
};

impl FrictionLawSpec for CoulombElastic {
    const NAME: &'static str = "coulomb_elastic";
    const PARAMS: &'static [ParamSpec] = &[MU, K_T];
    const STEADY_ONLY: bool = true;

    fn from_values(v: &[f64]) -> Self {
        Self::new(v[0], v[1])
    }

    fn values(&self) -> Vec<f64> {
        vec![self.mu, self.k_t]
    }

    fn is_active(&self) -> bool {
        self.mu != 0.0
    }

    fn kinetic_coefficient(&self) -> Option<f64> {
        Some(self.mu)
    }
}

impl FrictionLaw for CoulombElastic {
    /// `g`: the trial elastic slip (length); see the type's docs.
    #[inline]
    fn eval(&self, g: f64, t_n: f64, _delta: f64) -> FrictionValue {
        if t_n <= 0.0 {
            return FrictionValue::default();
        }
        let trial = -self.k_t * g;
        let bound = self.mu * t_n;
        if trial.abs() <= bound {
            FrictionValue {
                t: trial,
                d_w: -self.k_t,
                d_tn: 0.0,
                d_delta: 0.0,
            }
        } else {
            let s = trial.signum();
            FrictionValue {
                t: s * bound,
                d_w: 0.0,
                d_tn: s * self.mu,
                d_delta: 0.0,
            }
        }
    }
}

/// Rate-dependent (static/kinetic, Stribeck-type) friction:
/// t_T = −μ(|w|) t_n tanh(w/ε), μ(s) = μ_k + (μ_s − μ_k) exp(−s/v_s).
///
/// As ε → 0 and v_s → 0 with ε/v_s → 0 this tends to the classical static/kinetic Coulomb law
/// (static coefficient μ_s at w = 0, kinetic μ_k otherwise). With μ_s > μ_k the law is velocity
/// weakening (negative slope dμ/d|w|), the source of stick–slip.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RateDependent {
    /// Static coefficient μ_s ≥ 0 (the value of μ at |w| = 0).
    pub mu_s: f64,
    /// Kinetic coefficient μ_k ≥ 0 (the limit of μ as |w| → ∞).
    pub mu_k: f64,
    /// Decay velocity v_s > 0 of the static-to-kinetic transition.
    pub v_s: f64,
    /// Regularisation velocity ε > 0.
    pub eps: f64,
}

impl RateDependent {
    /// A law with static and kinetic coefficients, decay velocity `v_s` and regularisation `eps`.
    pub fn new(mu_s: f64, mu_k: f64, v_s: f64, eps: f64) -> Self {
        Self {
            mu_s,
            mu_k,
            v_s,
            eps,
        }
    }

    /// μ(s) and dμ/ds at s = |w| ≥ 0.
    #[inline]
    pub fn mu(&self, s: f64) -> (f64, f64) {
        let e = (-s / self.v_s).exp();
        let dm = self.mu_s - self.mu_k;
        (self.mu_k + dm * e, -dm * e / self.v_s)
    }
}

impl FrictionLawSpec for RateDependent {
    const NAME: &'static str = "rate_dependent";
    const PARAMS: &'static [ParamSpec] = &[
        ParamSpec {
            key: "mu_s",
            what: "static friction coefficient μ_s",
            unit: "–",
            bound: Bound::AtLeast(0.0),
            note: "",
        },
        ParamSpec {
            key: "mu_k",
            what: "kinetic friction coefficient μ_k",
            unit: "–",
            bound: Bound::AtLeast(0.0),
            note: "at most mu_s",
        },
        ParamSpec {
            key: "v_s",
            what: "decay velocity v_s",
            unit: "L/T (static: L)",
            bound: Bound::Above(0.0),
            note: "μ decays from mu_s to mu_k over it",
        },
        EPS,
    ];

    fn from_values(v: &[f64]) -> Self {
        Self::new(v[0], v[1], v[2], v[3])
    }

    fn values(&self) -> Vec<f64> {
        vec![self.mu_s, self.mu_k, self.v_s, self.eps]
    }

    fn is_active(&self) -> bool {
        self.mu_s != 0.0 || self.mu_k != 0.0
    }

    fn kinetic_coefficient(&self) -> Option<f64> {
        Some(self.mu_k)
    }

    /// μ_k ≤ μ_s (velocity weakening or neutral), checked where both are given and ≥ 0.
    fn cross_check(given: &dyn Fn(&str) -> Option<f64>) -> Vec<(&'static str, String)> {
        match (given("mu_s"), given("mu_k")) {
            (Some(mu_s), Some(mu_k)) if mu_s >= 0.0 && mu_k >= 0.0 && mu_k > mu_s => vec![(
                "mu_k",
                format!(
                    "kinetic coefficient μ_k = {mu_k} must not exceed the static coefficient \
                     μ_s = {mu_s}"
                ),
            )],
            _ => Vec::new(),
        }
    }
}

impl FrictionLaw for RateDependent {
    #[inline]
    fn eval(&self, w: f64, t_n: f64, _delta: f64) -> FrictionValue {
        if t_n <= 0.0 {
            return FrictionValue::default();
        }
        let s = w.abs();
        let (mu, dmu) = self.mu(s);
        let (phi, dphi) = tanh_with_derivative(w / self.eps);
        // d/dw [μ(|w|) tanh(w/ε)] = μ'(|w|) tanh(|w|/ε) + μ(|w|) sech²(w/ε)/ε (continuous at 0).
        let dg = dmu * phi.abs() + mu * dphi / self.eps;
        FrictionValue {
            t: -mu * t_n * phi,
            d_w: -t_n * dg,
            d_tn: -mu * phi,
            d_delta: 0.0,
        }
    }
}

/// Oden–Martins compliance-type friction: t_T = −c_T δ^{m_T} tanh(w/ε), independent of t_n.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct OdenMartins {
    /// Tangential compliance coefficient c_T ≥ 0.
    pub c_t: f64,
    /// Tangential compliance exponent m_T ≥ 1.
    pub m_t: f64,
    /// Regularisation velocity ε > 0.
    pub eps: f64,
}

impl OdenMartins {
    /// A law with coefficient `c_t`, exponent `m_t` and regularisation velocity `eps`.
    pub fn new(c_t: f64, m_t: f64, eps: f64) -> Self {
        Self { c_t, m_t, eps }
    }
}

impl FrictionLawSpec for OdenMartins {
    const NAME: &'static str = "oden_martins";
    const PARAMS: &'static [ParamSpec] = &[
        ParamSpec {
            key: "c_t",
            what: "tangential compliance coefficient c_t",
            unit: "F/L^(2+m_t)",
            bound: Bound::AtLeast(0.0),
            note: "",
        },
        ParamSpec {
            key: "m_t",
            what: "tangential compliance exponent m_t",
            unit: "–",
            bound: Bound::AtLeast(1.0),
            note: "",
        },
        EPS,
    ];
    const NEEDS_PENETRATION: bool = true;

    fn from_values(v: &[f64]) -> Self {
        Self::new(v[0], v[1], v[2])
    }

    fn values(&self) -> Vec<f64> {
        vec![self.c_t, self.m_t, self.eps]
    }

    fn is_active(&self) -> bool {
        self.c_t != 0.0
    }
}

impl FrictionLaw for OdenMartins {
    #[inline]
    fn eval(&self, w: f64, _t_n: f64, delta: f64) -> FrictionValue {
        if delta <= 0.0 {
            return FrictionValue::default();
        }
        let (pm, dpm) = pow_with_derivative(delta, self.m_t);
        let (phi, dphi) = tanh_with_derivative(w / self.eps);
        FrictionValue {
            t: -self.c_t * pm * phi,
            d_w: -self.c_t * pm * dphi / self.eps,
            d_tn: 0.0,
            d_delta: -self.c_t * dpm * phi,
        }
    }
}

/// Builds, from the list of registered law types, the [`Friction`] enum with its `match`
/// dispatch and the [`FrictionKind`] keyword enum (the scene's `law = "..."`), both from the
/// same entries. Each entry is a type implementing [`FrictionLawSpec`]; the variant of both
/// enums has the type's name. Frictionless contact (`None`, `"none"`) comes first in both.
macro_rules! friction_laws {
    ($($law:ident),+ $(,)?) => {
        /// The closed set of friction laws, dispatched statically by `match`: frictionless
        /// contact or one of the registered laws (scene `law =` is each law's
        /// [`FrictionLawSpec::NAME`], its keys are the law's [`FrictionLawSpec::PARAMS`]).
        ///
        /// Serialised as the scene's `[friction]` table: `law` and the law's parameters.
        #[derive(Debug, Clone, Copy, PartialEq, Default)]
        pub enum Friction {
            /// Frictionless contact: t_T = 0.
            #[default]
            None,
            $(
                #[doc = concat!("See [`", stringify!($law), "`].")]
                $law($law),
            )+
        }

        /// Which friction law, without its parameters: the keyword of `[friction] law`.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
        pub enum FrictionKind {
            /// No friction (frictionless contact), `"none"`.
            #[default]
            None,
            $(
                #[doc = concat!("[`", stringify!($law), "`].")]
                $law,
            )+
        }

        impl FrictionKind {
            /// Every kind, in registration order (`None` first).
            pub const ALL: &'static [FrictionKind] = &[FrictionKind::None, $(FrictionKind::$law),+];
            /// The scene keyword of every kind, in the order of [`Self::ALL`].
            pub const NAMES: &'static [&'static str] =
                &["none", $(<$law as FrictionLawSpec>::NAME),+];

            /// The scene keyword of this kind.
            pub fn as_str(self) -> &'static str {
                match self {
                    FrictionKind::None => "none",
                    $(FrictionKind::$law => <$law as FrictionLawSpec>::NAME,)+
                }
            }

            /// The parameters of this kind, in their declared order (none for `None`).
            pub fn params(self) -> &'static [ParamSpec] {
                match self {
                    FrictionKind::None => &[],
                    $(FrictionKind::$law => <$law as FrictionLawSpec>::PARAMS,)+
                }
            }

            /// Whether the law needs a penetration δ (see [`FrictionLawSpec::NEEDS_PENETRATION`]).
            pub fn needs_penetration(self) -> bool {
                match self {
                    FrictionKind::None => false,
                    $(FrictionKind::$law => <$law as FrictionLawSpec>::NEEDS_PENETRATION,)+
                }
            }

            /// Whether only the steady mode can use the law (see [`FrictionLawSpec::STEADY_ONLY`]).
            pub fn steady_only(self) -> bool {
                match self {
                    FrictionKind::None => false,
                    $(FrictionKind::$law => <$law as FrictionLawSpec>::STEADY_ONLY,)+
                }
            }

            /// The law's checks between parameters (see [`FrictionLawSpec::cross_check`]).
            pub fn cross_check(
                self,
                given: &dyn Fn(&str) -> Option<f64>,
            ) -> Vec<(&'static str, String)> {
                match self {
                    FrictionKind::None => Vec::new(),
                    $(FrictionKind::$law => <$law as FrictionLawSpec>::cross_check(given),)+
                }
            }

            /// The law of this kind from its parameter values, in the order of [`Self::params`].
            ///
            /// # Panics
            /// If `values` is shorter than [`Self::params`].
            pub fn build(self, values: &[f64]) -> Friction {
                match self {
                    FrictionKind::None => Friction::None,
                    $(FrictionKind::$law => Friction::$law(<$law as FrictionLawSpec>::from_values(values)),)+
                }
            }
        }

        impl Friction {
            /// Which law this is.
            pub fn kind(&self) -> FrictionKind {
                match self {
                    Friction::None => FrictionKind::None,
                    $(Friction::$law(_) => FrictionKind::$law,)+
                }
            }

            /// The parameter values, in the order of [`FrictionKind::params`].
            pub fn values(&self) -> Vec<f64> {
                match self {
                    Friction::None => Vec::new(),
                    $(Friction::$law(l) => l.values(),)+
                }
            }

            /// Whether the law can produce a non-zero traction (false for `None`, μ = 0 or
            /// c_T = 0), so that callers can skip friction work altogether.
            pub fn is_active(&self) -> bool {
                match self {
                    Friction::None => false,
                    $(Friction::$law(l) => l.is_active(),)+
                }
            }

            /// The friction coefficient at large slip (see
            /// [`FrictionLawSpec::kinetic_coefficient`]); `None` for frictionless contact.
            pub fn kinetic_coefficient(&self) -> Option<f64> {
                match self {
                    Friction::None => None,
                    $(Friction::$law(l) => l.kinetic_coefficient(),)+
                }
            }
        }

        impl FrictionLaw for Friction {
            #[inline]
            fn eval(&self, w: f64, t_n: f64, delta: f64) -> FrictionValue {
                match self {
                    Friction::None => FrictionValue::default(),
                    $(Friction::$law(l) => l.eval(w, t_n, delta),)+
                }
            }
        }
    };
}

friction_laws!(
    CoulombTanh,
    CoulombLinear,
    RateDependent,
    OdenMartins,
    CoulombElastic
);

impl LawKind for FrictionKind {
    type Law = Friction;
    const WHAT: &'static str = "friction law";

    fn kinds() -> &'static [Self] {
        Self::ALL
    }
    fn keyword(self) -> &'static str {
        self.as_str()
    }
    fn declared(self) -> &'static [ParamSpec] {
        self.params()
    }
    fn build_law(self, values: &[f64]) -> Friction {
        self.build(values)
    }
}

crate::params::law_kind_impls!(FrictionKind);

impl Friction {
    /// The scene-file name of the law.
    pub fn name(&self) -> &'static str {
        self.kind().as_str()
    }

    /// The regularisation velocity ε (None for frictionless contact).
    pub fn eps(&self) -> Option<f64> {
        let i = self.kind().params().iter().position(|p| p.key == "eps")?;
        self.values().get(i).copied()
    }

    /// Set the regularisation velocity ε (no effect for frictionless contact). Used by the
    /// steady solver's ε-homotopy, which walks ε down from a benign value to the scene's.
    pub fn set_eps(&mut self, eps: f64) {
        let kind = self.kind();
        if let Some(i) = kind.params().iter().position(|p| p.key == "eps") {
            let mut values = self.values();
            values[i] = eps;
            *self = kind.build(&values);
        }
    }

    /// Check the parameters against their declared bounds ([`ParamSpec::bound`]; all finite).
    pub fn validate(&self) -> Result<(), LawError> {
        for (p, &v) in self.kind().params().iter().zip(&self.values()) {
            check(p.key, v, p.bound.admits(v), &format!("must be {}", p.bound))?;
        }
        Ok(())
    }
}

impl Serialize for Friction {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let params = self.kind().params();
        let mut m = s.serialize_map(Some(1 + params.len()))?;
        m.serialize_entry("law", self.name())?;
        for (p, v) in params.iter().zip(self.values()) {
            m.serialize_entry(p.key, &v)?;
        }
        m.end()
    }
}

impl<'de> Deserialize<'de> for Friction {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        struct Tagged {
            #[serde(default)]
            law: FrictionKind,
            #[serde(flatten)]
            values: std::collections::BTreeMap<String, f64>,
        }
        let t = Tagged::deserialize(d)?;
        if let Some(key) = t
            .values
            .keys()
            .find(|k| !t.law.params().iter().any(|p| p.key == k.as_str()))
        {
            return Err(serde::de::Error::custom(format!(
                "`{key}` is not a parameter of friction law \"{}\"",
                t.law
            )));
        }
        t.law
            .build_from(|k| t.values.get(k).copied())
            .map_err(|key| {
                serde::de::Error::custom(format!("friction law \"{}\" needs `{key}`", t.law))
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Central difference of `f` at `x` with step `h`.
    fn cd(f: impl Fn(f64) -> f64, x: f64, h: f64) -> f64 {
        (f(x + h) - f(x - h)) / (2.0 * h)
    }

    fn assert_close(what: &str, got: f64, want: f64, rel: f64, abs: f64) {
        let err = (got - want).abs();
        assert!(
            err <= abs + rel * want.abs().max(got.abs()),
            "{what}: analytic {got:e} vs finite difference {want:e} (err {err:e})"
        );
    }

    /// Checks d_w, d_tn, d_delta of a friction law against central differences.
    fn check_friction_fd(law: &Friction, w: f64, t_n: f64, delta: f64, scale_w: f64) {
        let v = law.eval(w, t_n, delta);
        let hw = 1e-6 * scale_w.max(w.abs() * 1e-2).min(scale_w);
        let fd_w = cd(|x| law.eval(x, t_n, delta).t, w, hw);
        let tag = format!("{law:?} w={w:e} tn={t_n} delta={delta:e}");
        let t_scale = law.eval(1e9, t_n.max(1.0), delta.max(1.0)).t.abs().max(1.0);
        assert_close(
            &format!("d_w {tag}"),
            v.d_w,
            fd_w,
            1e-5,
            1e-9 * t_scale / scale_w,
        );
        let ht = 1e-6 * t_n.abs().max(1e-3);
        let fd_tn = cd(|x| law.eval(w, x, delta).t, t_n, ht);
        assert_close(&format!("d_tn {tag}"), v.d_tn, fd_tn, 1e-6, 1e-9);
        if delta > 0.0 {
            let hd = 1e-5 * delta;
            let fd_d = cd(|x| law.eval(w, t_n, x).t, delta, hd);
            assert_close(&format!("d_delta {tag}"), v.d_delta, fd_d, 1e-6, 1e-9);
        }
    }

    fn laws(eps: f64) -> Vec<Friction> {
        vec![
            Friction::CoulombTanh(CoulombTanh::new(0.3, eps)),
            Friction::CoulombLinear(CoulombLinear::new(0.3, eps)),
            Friction::RateDependent(RateDependent::new(0.6, 0.4, 20.0 * eps, eps)),
            Friction::RateDependent(RateDependent::new(0.6, 0.4, 0.1 * eps, eps)),
            Friction::RateDependent(RateDependent::new(0.3, 0.5, 3.0 * eps, eps)),
            Friction::OdenMartins(OdenMartins::new(250.0, 1.5, eps)),
            Friction::OdenMartins(OdenMartins::new(250.0, 1.0, eps)),
            Friction::OdenMartins(OdenMartins::new(250.0, 2.0, eps)),
            // k_T = 0.3 / ε: stick for |g| < ε t_n (the kink at |g| = ε t_n is avoided below).
            Friction::CoulombElastic(CoulombElastic::new(0.3, 0.3 / eps)),
        ]
    }

    /// Slip velocities sampled for the finite-difference checks, as multiples of ε: dense near 0,
    /// through the transition and far into sliding.
    fn slip_samples() -> Vec<f64> {
        let mut s = vec![0.0, 1e-9, 1e-6, 1e-3, 0.01, 0.1, 0.3, 0.5, 0.9, 0.99];
        s.extend([1.01, 1.1, 1.5, 2.0, 3.0, 5.0, 10.0, 30.0, 100.0]);
        let neg: Vec<f64> = s.iter().skip(1).map(|x| -x).collect();
        s.extend(neg);
        s
    }

    #[test]
    fn friction_derivatives_match_finite_differences() {
        let mut n = 0;
        for eps in [1e-4, 1e-2, 1.0, 50.0] {
            for law in laws(eps) {
                for s in slip_samples() {
                    // keep the linear law's kinks |w| = ε a margin away from the stencil
                    if matches!(law, Friction::CoulombLinear(_)) && ((s.abs() - 1.0).abs() < 1e-3) {
                        continue;
                    }
                    for t_n in [1e-3, 0.7, 150.0] {
                        // and the elastic-slip law's kink at k_T |g| = μ t_n, |g| = ε t_n
                        if matches!(law, Friction::CoulombElastic(_))
                            && (s.abs() / t_n - 1.0).abs() < 1e-3
                        {
                            continue;
                        }
                        for delta in [1e-7, 1e-3, 0.1, 2.0] {
                            check_friction_fd(&law, s * eps, t_n, delta, eps);
                            n += 1;
                        }
                    }
                }
            }
        }
        assert!(n > 1000);
    }

    #[test]
    fn rate_dependent_derivative_is_continuous_at_zero() {
        let law = RateDependent::new(0.6, 0.4, 0.01, 1e-3);
        let d0 = law.eval(0.0, 2.0, 0.0).d_w;
        // at w = 0 the derivative is −t_n μ_s / ε
        assert_close("d_w(0)", d0, -2.0 * 0.6 / 1e-3, 1e-14, 0.0);
        for w in [1e-12, 1e-10, 1e-8] {
            let dp = law.eval(w, 2.0, 0.0).d_w;
            let dm = law.eval(-w, 2.0, 0.0).d_w;
            assert_close("d_w(+w) vs d_w(0)", dp, d0, 1e-4, 0.0);
            assert_close("d_w even", dp, dm, 1e-14, 0.0);
        }
    }

    #[test]
    fn normal_compliance_derivatives_match_finite_differences() {
        for m_n in [1.0, 1.5, 2.0, 3.0] {
            for (b_n, l_n) in [(0.0, 0.0), (3.0, 0.0), (3.0, 1.0), (0.5, 1.5)] {
                let law = NormalCompliance::new(1e3, m_n, b_n, l_n);
                for delta in [1e-9, 1e-7, 1e-5, 1e-3, 0.01, 0.1, 0.5, 2.0] {
                    for rate in [0.0, 0.3, -0.01, 5.0, -1e-6] {
                        let v = law.eval(delta, rate);
                        if v.t == 0.0 {
                            continue; // clamp region, tested separately
                        }
                        let raw = |d: f64, r: f64| law.eval(d, r).t;
                        let hd = 1e-5 * delta;
                        let fd_d = cd(|d| raw(d, rate), delta, hd);
                        let tag =
                            format!("m_n={m_n} b_n={b_n} l_n={l_n} delta={delta:e} rate={rate}");
                        // round-off of the difference quotient: a few ulp of t over the step
                        let noise = 1e-15 * v.t.abs() / hd;
                        assert_close(&format!("d_delta {tag}"), v.d_delta, fd_d, 1e-6, noise);
                        // t_n is linear in δ̇: a large step only avoids round-off
                        let hr = 1e-4 * rate.abs().max(1.0);
                        if law.eval(delta, rate - hr).t == 0.0 {
                            continue;
                        }
                        let fd_r = cd(|r| raw(delta, r), rate, hr);
                        assert_close(&format!("d_rate {tag}"), v.d_rate, fd_r, 1e-6, 1e-12);
                    }
                }
            }
        }
    }

    #[test]
    fn smooth_clamp_derivatives_match_finite_differences() {
        // Raw values r = c δ^m + b δ^l δ̇ on both sides of 0 and of the width w, so that
        // points in the ramp (0 < r < w) and on the exact law (r ≥ w) are all checked.
        let w = 10.0;
        let mut in_ramp = 0;
        for m_n in [1.0, 2.0] {
            for (b_n, l_n) in [(0.0, 0.0), (5.0, 0.0), (500.0, 1.0)] {
                let law = NormalCompliance::new(2e4, m_n, b_n, l_n)
                    .with_clamp(Clamp::Smooth { width: w });
                for delta in [1e-5, 1e-4, 3e-4, 1e-3, 5e-3, 0.02] {
                    for rate in [-3.0, -1.0, -0.3, -0.05, 0.0, 0.2, 2.0] {
                        let v = law.eval(delta, rate);
                        if v.t == 0.0 {
                            assert_eq!(v, NormalValue::default());
                            continue;
                        }
                        let hard = NormalCompliance::new(2e4, m_n, b_n, l_n).eval(delta, rate);
                        if hard.t < w {
                            in_ramp += 1;
                        }
                        let tag =
                            format!("m_n={m_n} b_n={b_n} l_n={l_n} delta={delta:e} rate={rate}");
                        let hd = 1e-6 * delta;
                        let fd_d = cd(|d| law.eval(d, rate).t, delta, hd);
                        let noise = 1e-14 * v.t.abs().max(w) / hd;
                        assert_close(&format!("d_delta {tag}"), v.d_delta, fd_d, 1e-5, noise);
                        let hr = 1e-7 * rate.abs().max(1.0);
                        let fd_r = cd(|r| law.eval(delta, r).t, rate, hr);
                        let noise = 1e-14 * v.t.abs().max(w) / hr;
                        assert_close(&format!("d_rate {tag}"), v.d_rate, fd_r, 1e-5, noise);
                    }
                }
            }
        }
        assert!(in_ramp >= 10, "only {in_ramp} samples in the ramp");
    }

    #[test]
    fn smooth_clamp_is_c1_and_exact_outside_its_width() {
        let w = 4.0;
        let c = Clamp::Smooth { width: w };
        // C¹ at both ends of the ramp: value and slope continuous.
        let (v0, d0) = c.apply(1e-12);
        assert!(v0.abs() < 1e-20 && d0.abs() < 1e-11, "{v0} {d0}");
        let (vm, dm) = c.apply(w * (1.0 - 1e-12));
        let (vp, dp) = c.apply(w * (1.0 + 1e-12));
        assert!((vm - vp).abs() < 1e-10 && (dm - dp).abs() < 1e-10);
        // Exact law outside [0, w], below it and monotone inside.
        assert_eq!(c.apply(-1.0), (0.0, 0.0));
        assert_eq!(c.apply(7.5), (7.5, 1.0));
        let mut prev = 0.0;
        for k in 1..100 {
            let r = w * k as f64 / 100.0;
            let (v, d) = c.apply(r);
            assert!(v >= prev && v <= r && (0.0..=4.0 / 3.0 + 1e-12).contains(&d));
            assert!(r - v <= 4.0 * w / 27.0 + 1e-12);
            prev = v;
        }
        // The hard clamp is the default and leaves the law untouched.
        let law = NormalCompliance::new(100.0, 1.0, 50.0, 0.0);
        assert_eq!(law.clamp, Clamp::Hard);
        assert_eq!(law.eval(0.01, 0.1).t, 100.0 * 0.01 + 50.0 * 0.1);
        let smooth = law.with_clamp(Clamp::Smooth { width: 2.0 });
        // raw = 100·0.01 + 50·(−0.01) = 0.5 < w: rounded, below the raw value
        let (h, s) = (law.eval(0.01, -0.01).t, smooth.eval(0.01, -0.01).t);
        assert!((h - 0.5).abs() < 1e-12 && s > 0.0 && s < h, "{h} {s}");
        assert!(smooth.validate().is_ok());
        let bad = law.with_clamp(Clamp::Smooth { width: 0.0 });
        assert!(bad
            .validate()
            .unwrap_err()
            .to_string()
            .contains("clamp_width"));
    }

    #[test]
    fn normal_compliance_linear_penalty_is_exact() {
        let law = NormalCompliance::penalty(1e4);
        for delta in [1e-300, 1e-12, 0.5, 3.0] {
            let v = law.eval(delta, 0.7);
            assert_eq!(v.t, 1e4 * delta);
            assert_eq!(v.d_delta, 1e4);
            assert_eq!(v.d_rate, 0.0);
        }
        assert!(!law.has_damping());
        assert!(NormalCompliance::new(1.0, 1.0, 0.1, 0.0).has_damping());
    }

    #[test]
    fn normal_compliance_is_zero_out_of_contact_and_clamped() {
        let law = NormalCompliance::new(100.0, 1.5, 50.0, 1.0);
        for delta in [0.0, -1e-12, -1.0] {
            assert_eq!(law.eval(delta, 3.0), NormalValue::default());
            assert_eq!(law.eval(delta, -3.0), NormalValue::default());
        }
        // receding fast: 100 δ^1.5 + 50 δ δ̇ < 0  ⇔  δ̇ < −2 δ^0.5
        for delta in [1e-6f64, 1e-3, 0.1, 1.0] {
            let rate = -2.0 * delta.sqrt() * 1.01;
            assert_eq!(
                law.eval(delta, rate),
                NormalValue::default(),
                "delta={delta}"
            );
            let rate_ok = -2.0 * delta.sqrt() * 0.99;
            let v = law.eval(delta, rate_ok);
            assert!(v.t > 0.0 && v.d_rate > 0.0);
        }
        for delta in [1e-8, 1e-4, 1e-2, 1.0, 10.0] {
            for rate in [-100.0, -1.0, -1e-3, 0.0, 1.0] {
                assert!(law.eval(delta, rate).t >= 0.0);
            }
        }
    }

    #[test]
    fn normal_compliance_validation() {
        assert!(NormalCompliance::new(1.0, 1.0, 0.0, 0.0).validate().is_ok());
        let e = NormalCompliance::new(1.0, 0.5, 0.0, 0.0)
            .validate()
            .unwrap_err();
        assert!(e.to_string().contains("m_n"));
        assert!(NormalCompliance::new(0.0, 1.0, 0.0, 0.0)
            .validate()
            .is_err());
        assert!(NormalCompliance::new(f64::NAN, 1.0, 0.0, 0.0)
            .validate()
            .is_err());
        assert!(NormalCompliance::new(1.0, 1.0, -1.0, 0.0)
            .validate()
            .is_err());
    }

    #[test]
    fn friction_opposes_slip_and_is_bounded() {
        for eps in [1e-3, 0.1, 10.0] {
            for law in laws(eps) {
                let bound = |t_n: f64, delta: f64| match law {
                    Friction::CoulombTanh(l) => l.mu * t_n,
                    Friction::CoulombLinear(l) => l.mu * t_n,
                    Friction::RateDependent(l) => l.mu_s.max(l.mu_k) * t_n,
                    Friction::OdenMartins(l) => l.c_t * delta.powf(l.m_t),
                    Friction::CoulombElastic(l) => l.mu * t_n,
                    Friction::None => 0.0,
                };
                for s in slip_samples() {
                    let w = s * eps;
                    for t_n in [0.0, 1e-3, 1.0, 1e3] {
                        for delta in [0.0, 1e-4, 0.1] {
                            let v = law.eval(w, t_n, delta);
                            assert!(v.t * w <= 0.0, "{law:?} w={w} t={}", v.t);
                            assert!(
                                v.t.abs() <= bound(t_n, delta) * (1.0 + 1e-14),
                                "{law:?} w={w} t={} bound {}",
                                v.t,
                                bound(t_n, delta)
                            );
                            // slip resistance: t_T is non-increasing in w
                            assert!(v.d_w <= 0.0 || matches!(law, Friction::RateDependent(_)));
                        }
                    }
                }
            }
        }
        // velocity weakening: |t_T| decreases from ≈ μ_s t_n to μ_k t_n
        let l = RateDependent::new(0.6, 0.4, 1e-2, 1e-5);
        assert!((l.eval(1e-3, 1.0, 0.0).t + 0.6).abs() < 0.02);
        assert!((l.eval(1.0, 1.0, 0.0).t + 0.4).abs() < 1e-12);
        assert!(l.eval(0.05, 1.0, 0.0).d_w > 0.0);
    }

    #[test]
    fn negative_normal_traction_gives_no_friction() {
        for law in laws(0.1) {
            let v = law.eval(0.3, -5.0, 0.0);
            assert_eq!(v, FrictionValue::default(), "{law:?}");
        }
    }

    #[test]
    fn tanh_law_tends_to_sign_as_eps_vanishes() {
        let t_n = 2.0;
        let mu = 0.3;
        for w in [-1.0, -1e-3, 1e-3, 0.5] {
            let mut prev = f64::INFINITY;
            for k in 2..12 {
                let eps = 10f64.powi(-k);
                let t = CoulombTanh::new(mu, eps).eval(w, t_n, 0.0).t;
                let err = (t + mu * t_n * w.signum()).abs();
                assert!(err <= prev, "w={w} eps={eps}: error {err} grew from {prev}");
                prev = err;
            }
            assert!(prev < 1e-12, "w={w}: error {prev}");
        }
        // the same for the rate-dependent law with v_s = sqrt(ε): |t_T| → μ_k t_n for w ≠ 0
        for w in [-0.5, 0.2] {
            let eps: f64 = 1e-10;
            let t = RateDependent::new(0.6, 0.4, eps.sqrt(), eps)
                .eval(w, 1.0, 0.0)
                .t;
            assert!((t + 0.4 * w.signum()).abs() < 1e-12);
        }
        assert_eq!(CoulombTanh::new(mu, 1e-12).eval(0.0, t_n, 0.0).t, 0.0);
    }

    #[test]
    fn linear_law_is_piecewise_linear() {
        let l = CoulombLinear::new(0.5, 0.1);
        assert_eq!(l.eval(0.05, 2.0, 0.0).t, -0.5);
        assert_eq!(l.eval(0.05, 2.0, 0.0).d_w, -10.0);
        assert_eq!(l.eval(-0.3, 2.0, 0.0).t, 1.0);
        assert_eq!(l.eval(-0.3, 2.0, 0.0).d_w, 0.0);
        assert_eq!(l.eval(-0.3, 2.0, 0.0).d_tn, 0.5);
    }

    #[test]
    fn oden_martins_ignores_normal_traction() {
        let l = OdenMartins::new(100.0, 2.0, 0.01);
        let a = l.eval(0.02, 0.0, 0.1);
        let b = l.eval(0.02, 55.0, 0.1);
        assert_eq!(a, b);
        assert_eq!(a.d_tn, 0.0);
        assert_close("t", a.t, -100.0 * 0.01 * (2.0f64).tanh(), 1e-14, 0.0);
        assert_eq!(l.eval(0.02, 1.0, 0.0), FrictionValue::default());
        assert_eq!(l.eval(0.02, 1.0, -0.1), FrictionValue::default());
    }

    #[test]
    fn activity_and_validation() {
        assert!(!Friction::None.is_active());
        assert!(!Friction::CoulombTanh(CoulombTanh::new(0.0, 0.1)).is_active());
        assert!(Friction::CoulombTanh(CoulombTanh::new(0.3, 0.1)).is_active());
        assert!(!Friction::CoulombLinear(CoulombLinear::new(0.0, 0.1)).is_active());
        assert!(!Friction::RateDependent(RateDependent::new(0.0, 0.0, 1.0, 0.1)).is_active());
        assert!(Friction::RateDependent(RateDependent::new(0.0, 0.2, 1.0, 0.1)).is_active());
        assert!(!Friction::OdenMartins(OdenMartins::new(0.0, 1.0, 0.1)).is_active());
        assert!(Friction::OdenMartins(OdenMartins::new(5.0, 1.0, 0.1)).is_active());
        assert_eq!(Friction::None.eval(1.0, 1.0, 1.0), FrictionValue::default());

        for law in laws(0.1) {
            assert!(law.validate().is_ok(), "{law:?}");
        }
        let bad = Friction::RateDependent(RateDependent::new(0.6, 0.4, 0.0, 0.1));
        assert!(bad.validate().unwrap_err().to_string().contains("v_s"));
        let bad = Friction::CoulombTanh(CoulombTanh::new(0.3, 0.0));
        assert!(bad.validate().unwrap_err().to_string().contains("eps"));
        let bad = Friction::CoulombLinear(CoulombLinear::new(-0.3, 1.0));
        assert!(bad.validate().unwrap_err().to_string().contains("mu"));
        let bad = Friction::OdenMartins(OdenMartins::new(1.0, 0.5, 1.0));
        assert!(bad.validate().unwrap_err().to_string().contains("m_t"));
        assert!(Friction::None.validate().is_ok());
        for mut law in laws(0.1) {
            let before = law;
            law.set_eps(3e-4);
            if matches!(law, Friction::CoulombElastic(_)) {
                // No velocity regularisation: nothing to set.
                assert_eq!((law.eps(), law), (None, before));
            } else {
                assert_eq!(law.eps(), Some(3e-4), "{law:?}");
            }
        }
        let bad = Friction::CoulombElastic(CoulombElastic::new(0.3, 0.0));
        assert!(bad.validate().unwrap_err().to_string().contains("k_t"));
        let mut none = Friction::None;
        none.set_eps(1.0);
        assert_eq!(none.eps(), None);
    }

    #[test]
    fn law_declarations_are_consistent() {
        // Keywords are distinct, and a key shared by several laws is declared the same by all.
        let mut names = FrictionKind::NAMES.to_vec();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), FrictionKind::ALL.len());
        for key in FrictionKind::all_keys() {
            let first = FrictionKind::param(key).copied();
            for kind in FrictionKind::laws_with(key) {
                let p = kind.params().iter().find(|p| p.key == key).copied();
                assert_eq!(p, first, "`{key}` of {kind}");
            }
        }
        // Values go through build/values and serde unchanged, in the declared order.
        for kind in FrictionKind::ALL.iter().copied() {
            let values: Vec<f64> = (1..=kind.params().len()).map(|i| 0.5 + i as f64).collect();
            let law = kind.build(&values);
            assert_eq!(law.kind(), kind);
            assert_eq!(law.values(), values, "{kind}");
            assert_eq!(law.name(), kind.as_str());
            assert_eq!(kind.as_str().parse::<FrictionKind>(), Ok(kind));
            let json = serde_json::to_value(law).unwrap_or_default();
            let keys: Vec<&str> = json
                .as_object()
                .map(|m| {
                    m.keys()
                        .map(String::as_str)
                        .filter(|k| *k != "law")
                        .collect()
                })
                .unwrap_or_default();
            let mut declared: Vec<&str> = kind.params().iter().map(|p| p.key).collect();
            declared.sort_unstable();
            assert_eq!(keys, declared, "{kind}");
            let back: Friction = serde_json::from_value(json).unwrap_or_default();
            assert_eq!(back, law);
        }
        let missing: Result<Friction, _> =
            serde_json::from_str(r#"{"law":"coulomb_tanh","mu":0.3}"#);
        assert!(missing.is_err());
        let foreign: Result<Friction, _> =
            serde_json::from_str(r#"{"law":"coulomb_tanh","mu":0.3,"eps":0.1,"v_s":1}"#);
        assert!(foreign.is_err());
    }

    #[test]
    fn friction_serde_is_tagged_by_law_name() {
        let laws = [
            Friction::None,
            Friction::CoulombTanh(CoulombTanh::new(0.3, 1e-3)),
            Friction::CoulombLinear(CoulombLinear::new(0.3, 1e-3)),
            Friction::RateDependent(RateDependent::new(0.6, 0.4, 1e-2, 1e-4)),
            Friction::OdenMartins(OdenMartins::new(10.0, 1.5, 1e-3)),
        ];
        for law in laws {
            let json = serde_json::to_string(&law).unwrap_or_default();
            assert!(
                json.contains(&format!("\"law\":\"{}\"", law.name())),
                "{json}"
            );
            let back: Friction = serde_json::from_str(&json).unwrap_or_default();
            assert_eq!(back, law);
        }
        let parsed: Result<Friction, _> = serde_json::from_str(
            r#"{"law":"rate_dependent","mu_s":0.6,"mu_k":0.4,"v_s":0.01,"eps":1e-4}"#,
        );
        assert!(matches!(parsed, Ok(Friction::RateDependent(_))));
    }
}
