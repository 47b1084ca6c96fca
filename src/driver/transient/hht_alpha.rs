//! Hilber–Hughes–Taylor α (HHT-α), the α-method of Abaqus/Standard's implicit dynamics: the
//! generalized-α step with no acceleration averaging,
//!
//! ```text
//!   M a_{n+1} + (1 − α) f(u_{n+1}, v_{n+1}) + α f(u_n, v_n) = 0,
//!   α = (1 − ρ∞)/(1 + ρ∞) ∈ [0, 1/3],  γ = 1/2 + α,  β = (1 + α)²/4,
//! ```
//!
//! with ρ∞ ∈ [1/2, 1] the spectral radius at infinity (ρ∞ = 1: the trapezoidal rule). Second
//! order, unconditionally stable for linear problems, and dissipative in the high frequencies
//! (less selectively than generalized-α at equal ρ∞). The forces are averaged, like the
//! generalized-α step of this program, so every force is evaluated at an actual configuration.
//! Hilber, Hughes & Taylor, Earthquake Eng. Struct. Dyn. 5 (1977) 283–292, written in the
//! notation of Chung & Hulbert, J. Appl. Mech. 60 (1993) 371–375 (α_m = 0, α_f = α).

use super::integrator::IntegratorSpec;
use super::{GenAlpha, Scheme};

/// The scene's `"hht_alpha"`: the one-step loop of [`super::integrate`] with the HHT parameters.
pub struct HhtAlpha;

/// The HHT-α parameters for spectral radius at infinity `rho_inf` (clamped to [1/2, 1]).
pub fn hht_parameters(rho_inf: f64) -> GenAlpha {
    let r = rho_inf.clamp(0.5, 1.0);
    let af = (1.0 - r) / (1.0 + r);
    GenAlpha {
        rho_inf: r,
        am: 0.0,
        af,
        gamma: 0.5 + af,
        beta: 0.25 * (1.0 + af).powi(2),
    }
}

impl IntegratorSpec for HhtAlpha {
    fn scheme_3d(rho_inf: f64) -> Option<Scheme<crate::model::Solid3DSystem>> {
        Some(Scheme::generalized_alpha(hht_parameters(rho_inf)))
    }

    fn scheme(rho_inf: f64) -> Scheme {
        Scheme::generalized_alpha(hht_parameters(rho_inf))
    }
}
