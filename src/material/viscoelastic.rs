//! Viscoelastic overstress laws with a Prony kernel and internal variables at quadrature points.
//!
//! A viscoelastic material is a hyperelastic law ([`super::Material`], the *equilibrium* or
//! fully relaxed response) plus a rate-dependent overstress `S_v` (second Piola–Kirchhoff), so
//! that the first Piola–Kirchhoff stress is `P = ∂W/∂F + F S_v`. The overstress relaxes with the
//! Prony kernel
//!
//! ```text
//! k(s) = Σ_i g_i exp(−s/τ_i),      s ≥ 0
//! ```
//!
//! **Units.** `g_i` are dimensionless weights, `τ_i` are times (the scene's time unit, e.g. s),
//! and `γ` is a stress (the scene's stress unit, e.g. psi). At small strain both models below add
//! a shear relaxation modulus `ΔG(t) = (γ/2) k(t)` (and no bulk relaxation: `λ_v = 0`) to the
//! elastic law, so a standard linear solid with `G(t) = G_∞ + G_1 exp(−t/τ)` is the elastic law
//! with `G = G_∞` plus `γ = 2 G_1`, `prony = [[1, τ]]`.
//!
//! # Models ([`ViscoModel`])
//!
//! **`Convolution`** — the linear viscoelastic perturbation of a hyperelastic law,
//!
//! ```text
//! S = ∂W/∂E + γ ∫_{−∞}^t k(t − s) Ė(s) ds = ∂W/∂E + γ Σ_i Q_i,     Q̇_i + Q_i/τ_i = g_i Ė,
//! ```
//!
//! `E = (C − I)/2` the Green strain (in-plane; `E33 = 0` in plane strain). For `E` linear in
//! time over a step `[t_n, t_n + Δt]` the ODE is integrated exactly:
//!
//! ```text
//! Q_i^{n+1} = a_i Q_i^n + g_i φ_i (E^{n+1} − E^n),   a_i = exp(−Δt/τ_i),   φ_i = (1 − a_i) τ_i/Δt
//! ```
//!
//! (`φ_i → 1` as `Δt → 0`: the instantaneous response `γ k(0) ΔE`; `φ_i → 0` as `Δt → ∞`).
//!
//! **Energy.** Each Prony term is a Maxwell element in the Green strain: a spring `γ g_i` in
//! series with a dashpot, `Q_i = g_i (E − E_v,i)`, storing `γ/(2 g_i) |Q_i|²` and dissipating
//! `γ/(g_i τ_i) |Q_i|² ≥ 0`. The overstress power is `P_v : Ḟ = S_v : Ė` (a rigid rotation
//! `Ḟ = W F` gives `FᵀḞ` skew and no power), so the model cannot create energy along any path,
//! at any strain or spin, even though its stress is not the derivative of a free energy of `F`
//! alone. [`Viscoelastic::stored_energy`] and [`Viscoelastic::step_work`] give the balance
//! that the transient mode reports (`results.viscous_energy`), with a flag should a run ever
//! show the overstress creating energy.
//!
//! **`Multiplicative`** — a thermodynamically consistent finite-strain model: per Prony term a
//! Sidoroff split `F = F_e F_v`, viscous right Cauchy–Green tensor `C_v = F_vᵀ F_v` and a
//! compressible neo-Hookean non-equilibrium energy on `C_e = F_v⁻ᵀ C F_v⁻¹`,
//!
//! ```text
//! ψ_i = μ_i/2 (tr(C C_v⁻¹) − 3 − ln det(C C_v⁻¹)),   μ_i = γ g_i / 2,
//! S_i = 2 ∂ψ_i/∂C = μ_i (C_v⁻¹ − C⁻¹),
//! ```
//!
//! with the Reese–Govindjee (1998) evolution `−½ (L_v b_e) b_e⁻¹ = 𝒱⁻¹ : τ_i` for an isotropic
//! viscosity `𝒱⁻¹ = 𝕀/(2η_i)`, `η_i = μ_i τ_i`. Pulled back to the reference configuration this
//! is the *linear* law `Ċ_v = (C − C_v)/τ_i`. The dissipation
//!
//! ```text
//! D_i = −∂ψ_i/∂C_v : Ċ_v = μ_i/(2τ_i) tr(A G A G) ≥ 0,    A = C − C_v,  G = C_v⁻¹ (SPD)
//! ```
//!
//! is non-negative for every path. The state stores `E_v = (C_v − I)/2` (so that small strains
//! keep full precision); it obeys `Ė_v = (E − E_v)/τ_i`, integrated exactly for `E` linear over the
//! step: `E_v^{n+1} = a E_v^n + (φ − a) E^n + (1 − φ) E^{n+1}` (a non-negative combination, so
//! `C_v` stays positive definite). In plane strain `C_v33 = 1` for all time (it starts at 1 and
//! `C33 = 1`), so the state is in-plane. Linearised, `Q_i = 2μ_i (E − E_v)` obeys exactly the
//! convolution model's ODE: both models agree at small strain.
//!
//! # State layout
//!
//! `3 (1 + n)` values per quadrature point for `n` Prony terms in plane strain: the Green strain
//! `E^n` of the committed state (`[E11, E22, E12]`), then per term `[Q11, Q22, Q12]`
//! (convolution) or `[Ev11, Ev22, Ev12]` (multiplicative). In three dimensions the same with six
//! values per symmetric tensor in Voigt order `[11, 22, 33, 23, 13, 12]`, `6 (1 + n)` in all
//! ([`Viscoelastic::n_state_of`]). Every function is generic in the dimension
//! ([`crate::math::Tensor`]): the 3D model is the same code on `Mat3`, and a plane-strain path
//! run in 3D keeps an in-plane state and gives the 2D overstress. The initial state (all zeros) is the undisturbed,
//! stress-free reference. Elastic materials have no state at all.
//!
//! The update is a pure function: the start-of-step state, the step `Δt` and the end-of-step
//! `∇u` go in; the end-of-step overstress, its algorithmic tangent `∂P_v/∂F` and the new state
//! come out. The caller decides whether to keep the new state (only on convergence).

use super::Constitutive;
use super::Material;
use crate::math::{Mat2, Tangent, Tensor};

/// Largest number of Prony terms (the state is kept in fixed-size stack buffers).
pub const MAX_PRONY: usize = 8;

/// Largest number of state values per quadrature point in plane strain.
pub const MAX_STATE: usize = 3 * (1 + MAX_PRONY);

/// Largest number of state values per quadrature point in three dimensions.
pub const MAX_STATE_3D: usize = 6 * (1 + MAX_PRONY);

/// Which viscoelastic model (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViscoModel {
    /// The linear convolution on the Green strain rate (the perturbation of a hyperelastic law).
    Convolution,
    /// The multiplicative (Sidoroff / Reese–Govindjee) finite-strain model.
    Multiplicative,
}

impl ViscoModel {
    /// Scene names of the models.
    pub const NAMES: &'static [&'static str] = &["convolution", "multiplicative"];

    /// The model with scene name `s`.
    pub fn from_name(s: &str) -> Option<Self> {
        match s {
            "convolution" => Some(Self::Convolution),
            "multiplicative" => Some(Self::Multiplicative),
            _ => None,
        }
    }

    /// Scene name.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Convolution => "convolution",
            Self::Multiplicative => "multiplicative",
        }
    }
}

/// Error building a [`Viscoelastic`] law from user parameters.
#[derive(Clone, Debug, PartialEq)]
pub enum ViscoError {
    /// No Prony term, or more than [`MAX_PRONY`].
    TermCount(usize),
    /// `g_i` not finite or negative, or `τ_i` not finite and positive (term index, g, τ).
    BadTerm(usize, f64, f64),
    /// `γ` not finite or negative.
    BadGamma(f64),
}

impl std::fmt::Display for ViscoError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::TermCount(n) => write!(f, "needs between 1 and {MAX_PRONY} Prony terms, got {n}"),
            Self::BadTerm(i, g, t) => write!(
                f,
                "Prony term {i} = [{g}, {t}]: needs g >= 0 (finite) and tau > 0 (finite)"
            ),
            Self::BadGamma(g) => write!(f, "gamma = {g}: needs a finite value >= 0"),
        }
    }
}

/// The viscous overstress of a viscoelastic material: model, `γ` and the Prony series.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Viscoelastic {
    pub model: ViscoModel,
    /// Stress scale `γ` (stress units).
    pub gamma: f64,
    /// `(g_i, τ_i)`, the first `n` entries used.
    terms: [(f64, f64); MAX_PRONY],
    n: usize,
}

/// Green strain `E = (H + Hᵀ + HᵀH)/2` from `H = ∇u` (no cancellation at small strain).
#[inline(always)]
pub fn green_strain<T: Tensor>(h: &T) -> T {
    (*h + h.transposed() + h.transposed().dot(h)) * 0.5
}

/// `(a, φ)` of the exponential integrator for `h = Δt/τ ≥ 0`: `a = e^{−h}`,
/// `φ = (1 − e^{−h})/h` (→ 1 as h → 0).
#[inline(always)]
pub fn exp_weights(h: f64) -> (f64, f64) {
    let a = (-h).exp();
    let phi = if h < 1e-8 {
        1.0 - 0.5 * h
    } else {
        -(-h).exp_m1() / h
    };
    (a, phi)
}

/// `∂E/∂F_kL = ½(e_kLᵀ F + Fᵀ e_kL)` for the unit tensor `e_kL`.
#[inline(always)]
fn de_df<T: Tensor>(f: &T, k: usize, l: usize) -> T {
    let mut e = T::zero();
    e[(k, l)] = 1.0;
    (e.transposed().dot(f) + f.transposed().dot(&e)) * 0.5
}

/// Values `[ns·(1 + i), ns·(2 + i))` of a state: the internal variable of Prony term `i`.
#[inline(always)]
fn term(state: &[f64], ns: usize, i: usize) -> &[f64] {
    &state[ns * (1 + i)..ns * (2 + i)]
}

impl Viscoelastic {
    /// A law with the given model, `γ` and Prony terms `(g_i, τ_i)`; checks the parameters.
    pub fn new(model: ViscoModel, gamma: f64, prony: &[(f64, f64)]) -> Result<Self, ViscoError> {
        if prony.is_empty() || prony.len() > MAX_PRONY {
            return Err(ViscoError::TermCount(prony.len()));
        }
        if !(gamma.is_finite() && gamma >= 0.0) {
            return Err(ViscoError::BadGamma(gamma));
        }
        let mut terms = [(0.0, 1.0); MAX_PRONY];
        for (i, &(g, tau)) in prony.iter().enumerate() {
            if !(g.is_finite() && g >= 0.0 && tau.is_finite() && tau > 0.0) {
                return Err(ViscoError::BadTerm(i, g, tau));
            }
            terms[i] = (g, tau);
        }
        Ok(Self {
            model,
            gamma,
            terms,
            n: prony.len(),
        })
    }

    /// The Prony terms `(g_i, τ_i)`.
    pub fn prony(&self) -> &[(f64, f64)] {
        &self.terms[..self.n]
    }

    /// The kernel `k(s) = Σ g_i exp(−s/τ_i)`.
    pub fn kernel(&self, s: f64) -> f64 {
        self.prony().iter().map(|(g, t)| g * (-s / t).exp()).sum()
    }

    /// Instantaneous extra shear modulus `γ k(0) / 2` of the small-strain limit.
    pub fn instantaneous_shear_modulus(&self) -> f64 {
        0.5 * self.gamma * self.kernel(0.0)
    }

    /// State values per quadrature point in plane strain.
    pub fn n_state(&self) -> usize {
        self.n_state_of::<Mat2>()
    }

    /// State values per quadrature point in the dimension of `T`: `NSYM (1 + n)`.
    pub fn n_state_of<T: Tensor>(&self) -> usize {
        T::NSYM * (1 + self.n)
    }

    /// End-of-step overstress `P_v = F S_v` at `∇u = h` (`Mat2` in plane strain or `Mat3`),
    /// from the committed state `old` over a step `dt ≥ 0`; the new state goes to `new` (same
    /// length as `old`). With `with_tangent`, also `∂P_v/∂F` (the algorithmic tangent; zeros
    /// otherwise).
    pub fn overstress<T: Tensor>(
        &self,
        h: &T,
        old: &[f64],
        dt: f64,
        new: &mut [f64],
        with_tangent: bool,
    ) -> (T, T::Tangent) {
        let (d, ns) = (T::D, T::NSYM);
        let f = T::eye() + *h;
        let e1 = green_strain(h);
        let e0 = T::sym_from(&old[0..ns]);
        e1.sym_store(&mut new[0..ns]);
        let mut a_t = T::tangent_zero();
        let mut de = [T::zero(); 9];
        if with_tangent {
            for (kl, dek) in de.iter_mut().enumerate().take(d * d) {
                *dek = de_df(&f, kl / d, kl % d);
            }
        }
        let mut s_v = T::zero();
        match self.model {
            ViscoModel::Convolution => {
                // S_v = γ Σ Q_i; ∂S_v/∂E = γ Σ g_i φ_i (identity on symmetric tensors).
                let mut c_tan = 0.0;
                let de_step = e1 - e0;
                for (i, &(g, tau)) in self.prony().iter().enumerate() {
                    let (a, phi) = exp_weights(dt / tau);
                    let q = T::sym_from(term(old, ns, i)) * a + de_step * (g * phi);
                    q.sym_store(&mut new[ns * (1 + i)..ns * (2 + i)]);
                    s_v = s_v + q;
                    c_tan += g * phi;
                }
                s_v = s_v * self.gamma;
                if with_tangent {
                    c_tan *= self.gamma;
                    for (kl, dek) in de.iter().enumerate().take(d * d) {
                        let (k, l) = (kl / d, kl % d);
                        let mut e = T::zero();
                        e[(k, l)] = 1.0;
                        let dp = e.dot(&s_v) + f.dot(dek) * c_tan;
                        for i in 0..d {
                            for j in 0..d {
                                a_t[(T::flat(i, j), kl)] = dp[(i, j)];
                            }
                        }
                    }
                }
            }
            ViscoModel::Multiplicative => {
                let jm1 = h.det_ipm1();
                if jm1 <= -1.0 || !jm1.is_finite() {
                    return (T::filled(f64::INFINITY), T::tangent_filled(f64::INFINITY));
                }
                let c = f.transposed().dot(&f);
                let c_inv = c.inverse().unwrap_or(T::filled(f64::INFINITY));
                let mut dsv = [T::zero(); 9];
                for (i, &(g, tau)) in self.prony().iter().enumerate() {
                    let mu = 0.5 * self.gamma * g;
                    let (a, phi) = exp_weights(dt / tau);
                    let ev0 = T::sym_from(term(old, ns, i));
                    let ev = ev0 * a + e0 * (phi - a) + e1 * (1.0 - phi);
                    ev.sym_store(&mut new[ns * (1 + i)..ns * (2 + i)]);
                    let cv = T::eye() + ev * 2.0;
                    let Some(gi) = cv.inverse() else {
                        return (T::filled(f64::INFINITY), T::tangent_filled(f64::INFINITY));
                    };
                    // S_i = μ (C_v⁻¹ − C⁻¹) = 2μ C_v⁻¹ (E − E_v) C⁻¹, symmetrised.
                    let si = gi.dot(&(e1 - ev)).dot(&c_inv) * (2.0 * mu);
                    s_v = s_v + (si + si.transposed()) * 0.5;
                    if with_tangent {
                        // dS_i = μ [−(1 − φ) G dC G + C⁻¹ dC C⁻¹], dC = 2 dE.
                        for (dsk, dek) in dsv.iter_mut().zip(de.iter()).take(d * d) {
                            let dc = *dek * 2.0;
                            *dsk = *dsk
                                + (c_inv.dot(&dc).dot(&c_inv) - gi.dot(&dc).dot(&gi) * (1.0 - phi))
                                    * mu;
                        }
                    }
                }
                if with_tangent {
                    for (kl, dsk) in dsv.iter().enumerate().take(d * d) {
                        let (k, l) = (kl / d, kl % d);
                        let mut e = T::zero();
                        e[(k, l)] = 1.0;
                        let dp = e.dot(&s_v) + f.dot(dsk);
                        for i in 0..d {
                            for j in 0..d {
                                a_t[(T::flat(i, j), kl)] = dp[(i, j)];
                            }
                        }
                    }
                }
            }
        }
        (f.dot(&s_v), a_t)
    }

    /// The overstress `S_v` (second Piola–Kirchhoff) that a committed plane-strain state holds
    /// (see [`Self::state_overstress_of`]).
    pub fn state_overstress(&self, state: &[f64]) -> Mat2 {
        self.state_overstress_of::<Mat2>(state)
    }

    /// The overstress `S_v` (second Piola–Kirchhoff) that a committed state holds: its Green
    /// strain `E` (the first `NSYM` values) and internal variables give `γ Σ Q_i`
    /// (convolution) or `Σ μ_i (C_v⁻¹ − C⁻¹)` (multiplicative).
    pub fn state_overstress_of<T: Tensor>(&self, state: &[f64]) -> T {
        let ns = T::NSYM;
        let mut s_v = T::zero();
        match self.model {
            ViscoModel::Convolution => {
                for i in 0..self.n {
                    s_v = s_v + T::sym_from(term(state, ns, i));
                }
                s_v * self.gamma
            }
            ViscoModel::Multiplicative => {
                let c = T::eye() + T::sym_from(&state[0..ns]) * 2.0;
                let Some(c_inv) = c.inverse() else {
                    return T::filled(f64::INFINITY);
                };
                for (i, &(g, _)) in self.prony().iter().enumerate() {
                    let cv = T::eye() + T::sym_from(term(state, ns, i)) * 2.0;
                    let Some(gi) = cv.inverse() else {
                        return T::filled(f64::INFINITY);
                    };
                    s_v = s_v + (gi - c_inv) * (0.5 * self.gamma * g);
                }
                s_v
            }
        }
    }

    /// Stored energy of a committed plane-strain state (see [`Self::stored_energy_of`]).
    pub fn stored_energy(&self, state: &[f64]) -> f64 {
        self.stored_energy_of::<Mat2>(state)
    }

    /// Energy per unit reference volume stored in the internal variables of a committed state:
    /// the Maxwell springs of the convolution model, `Σ γ/(2 g_i) |Q_i|²` (its `Q̇_i + Q_i/τ_i =
    /// g_i Ė` is a spring `γ g_i` in series with a dashpot, `Q_i = g_i (E − E_v,i)`), or the
    /// non-equilibrium energy `Σ ψ_i` of the multiplicative model. Either way the overstress
    /// power is `S_v : Ė = d/dt (stored) + D` with a dissipation `D ≥ 0` for every path.
    pub fn stored_energy_of<T: Tensor>(&self, state: &[f64]) -> f64 {
        let (d, ns) = (T::D, T::NSYM);
        match self.model {
            ViscoModel::Convolution => {
                let mut w = 0.0;
                for (i, &(g, _)) in self.prony().iter().enumerate() {
                    if g > 0.0 {
                        let q = term(state, ns, i);
                        // |Q|² in the symmetric layout: diagonal once, off-diagonal twice.
                        let diag: f64 = q[..d].iter().map(|x| x * x).sum();
                        let off: f64 = q[d..ns].iter().map(|x| x * x).sum();
                        w += 0.5 * self.gamma / g * (diag + 2.0 * off);
                    }
                }
                w
            }
            ViscoModel::Multiplicative => {
                let c = T::eye() + T::sym_from(&state[0..ns]) * 2.0;
                let mut psi = 0.0;
                for (i, &(g, _)) in self.prony().iter().enumerate() {
                    let cv = T::eye() + T::sym_from(term(state, ns, i)) * 2.0;
                    let Some(gi) = cv.inverse() else {
                        return f64::INFINITY;
                    };
                    let ce = c.dot(&gi);
                    let det = ce.det();
                    if det.is_nan() || det <= 0.0 {
                        return f64::INFINITY;
                    }
                    psi += 0.25 * self.gamma * g * (ce.tr() - d as f64 - det.ln());
                }
                psi
            }
        }
    }

    /// Overstress work over a committed plane-strain step (see [`Self::step_work_of`]).
    pub fn step_work(&self, old: &[f64], new: &[f64]) -> f64 {
        self.step_work_of::<Mat2>(old, new)
    }

    /// Work per unit reference volume of the overstress over one committed step from state
    /// `old` to state `new`, `∫ S_v : Ė dt` by the trapezoidal rule
    /// `½ (S_v^n + S_v^{n+1}) : (E^{n+1} − E^n)`.
    pub fn step_work_of<T: Tensor>(&self, old: &[f64], new: &[f64]) -> f64 {
        let ns = T::NSYM;
        let de = T::sym_from(&new[0..ns]) - T::sym_from(&old[0..ns]);
        let s = (self.state_overstress_of::<T>(old) + self.state_overstress_of::<T>(new)) * 0.5;
        s.ddot(&de)
    }

    /// Non-equilibrium free energy `Σ ψ_i` at `∇u = h` with the internal state `state`
    /// (multiplicative model; `None` for the convolution model, which has none).
    pub fn free_energy<T: Tensor>(&self, h: &T, state: &[f64]) -> Option<f64> {
        if self.model != ViscoModel::Multiplicative {
            return None;
        }
        let ns = T::NSYM;
        let f = T::eye() + *h;
        let c = f.transposed().dot(&f);
        let mut psi = 0.0;
        for (i, &(g, _)) in self.prony().iter().enumerate() {
            let mu = 0.5 * self.gamma * g;
            let cv = T::eye() + T::sym_from(term(state, ns, i)) * 2.0;
            let gi = cv.inverse()?;
            let ce = c.dot(&gi);
            let det = ce.det();
            if det.is_nan() || det <= 0.0 {
                return Some(f64::INFINITY);
            }
            psi += 0.5 * mu * (ce.tr() - T::D as f64 - det.ln());
        }
        Some(psi)
    }

    /// Dissipation rate `D = Σ μ_i/(2τ_i) tr(A G A G)` of the multiplicative model at `∇u = h`
    /// with internal state `state` (`None` for the convolution model).
    pub fn dissipation_rate<T: Tensor>(&self, h: &T, state: &[f64]) -> Option<f64> {
        if self.model != ViscoModel::Multiplicative {
            return None;
        }
        let ns = T::NSYM;
        let e = green_strain(h);
        let mut d = 0.0;
        for (i, &(g, tau)) in self.prony().iter().enumerate() {
            let mu = 0.5 * self.gamma * g;
            let ev = T::sym_from(term(state, ns, i));
            let gi = (T::eye() + ev * 2.0).inverse()?;
            let a = (e - ev) * 2.0;
            let agag = a.dot(&gi).dot(&a).dot(&gi);
            d += mu / (2.0 * tau) * agag.tr();
        }
        Some(d)
    }
}

/// An elastic law with a viscoelastic overstress: `P = ∂W/∂F + F S_v`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViscoelasticMaterial {
    pub elastic: Material,
    pub visco: Viscoelastic,
}

impl Constitutive for ViscoelasticMaterial {
    fn n_state(&self) -> usize {
        self.visco.n_state()
    }

    fn update(
        &self,
        grad_u: &Mat2,
        old: &[f64],
        dt: f64,
        new: &mut [f64],
        with_tangent: bool,
    ) -> (Mat2, Tangent) {
        use super::Hyperelastic;
        let (mut p, mut a) = if with_tangent {
            self.elastic.stress_tangent(grad_u)
        } else {
            (self.elastic.stress(grad_u), Tangent::zeros())
        };
        let (pv, av) = self.visco.overstress(grad_u, old, dt, new, with_tangent);
        p += pv;
        a += av;
        (p, a)
    }

    fn free_energy(&self, grad_u: &Mat2, state: &[f64]) -> Option<f64> {
        use super::Hyperelastic;
        let psi = self.visco.free_energy(grad_u, state)?;
        Some(self.elastic.energy(grad_u) + psi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::fd_check::{check_stateful, SplitMix};
    use crate::material::{MooneyRivlin, MooneyRivlinIncompressible, NeoHookean};
    use crate::math::{det_identity_plus_minus_one, embed_plane, Mat3, Tangent3};

    fn laws() -> Vec<ViscoelasticMaterial> {
        let prony = [(0.6, 0.05), (0.3, 1.3), (0.1, 20.0)];
        let mut out = Vec::new();
        for model in [ViscoModel::Convolution, ViscoModel::Multiplicative] {
            let visco = Viscoelastic::new(model, 3.0, &prony).unwrap();
            for elastic in [
                Material::from(NeoHookean::new(1.5, 4.0)),
                Material::from(MooneyRivlin::new(0.8, 0.2, 20.0)),
                Material::from(MooneyRivlinIncompressible::new(0.8, 0.2)),
            ] {
                out.push(ViscoelasticMaterial { elastic, visco });
            }
        }
        out
    }

    /// Random admissible `∇u` with |∇u| up to `scale` and `J ∈ (0.5, 2)`.
    fn random_grad(rng: &mut SplitMix, scale: f64) -> Mat2 {
        loop {
            let h = Mat2::from_fn(|_, _| scale * (2.0 * rng.next() - 1.0));
            let j = 1.0 + det_identity_plus_minus_one(&h);
            if j > 0.5 && j < 2.0 {
                return h;
            }
        }
    }

    /// Random history: a few random steps from the reference.
    fn random_state(m: &ViscoelasticMaterial, rng: &mut SplitMix) -> Vec<f64> {
        let n = m.n_state();
        let mut s = vec![0.0; n];
        let mut s1 = vec![0.0; n];
        for _ in 0..3 {
            let h = random_grad(rng, 0.4);
            let dt = 0.5 * rng.next();
            m.update(&h, &s, dt, &mut s1, false);
            s.copy_from_slice(&s1);
        }
        s
    }

    #[test]
    fn tangent_with_history_matches_finite_differences() {
        let mut rng = SplitMix(7);
        let mut worst = 0.0_f64;
        for m in laws() {
            for _ in 0..40 {
                let old = random_state(&m, &mut rng);
                let h = random_grad(&mut rng, 0.5);
                let dt = [0.0, 1e-3, 0.1, 2.0, 100.0][(rng.next() * 5.0) as usize % 5];
                let r = check_stateful(&m, &h, &old, dt);
                assert!(
                    r.stress_rel_err < 1e-6 && r.tangent_rel_err < 1e-6,
                    "{m:?} at {h}, dt {dt}: {r:?}"
                );
                worst = worst.max(r.tangent_rel_err).max(r.stress_rel_err);
            }
        }
        println!("viscoelastic FD with history: worst rel err {worst:.2e}");
    }

    #[test]
    fn zero_step_keeps_the_state_and_step_is_exact_for_linear_strain() {
        // Δt = 0: the committed state is returned unchanged (the stress of a committed state).
        let mut rng = SplitMix(3);
        for m in laws() {
            let old = random_state(&m, &mut rng);
            let h = Mat2::new(old[0], old[2], old[2], old[1]);
            // ∇u with Green strain E^n: the symmetric square root of C = I + 2E, minus I.
            let c = Mat2::identity() + h * 2.0;
            let eig = c.symmetric_eigen();
            let u = eig.eigenvectors
                * Mat2::from_diagonal(&eig.eigenvalues.map(f64::sqrt))
                * eig.eigenvectors.transpose();
            let mut new = vec![0.0; m.n_state()];
            m.update(&(u - Mat2::identity()), &old, 0.0, &mut new, false);
            for (a, b) in old.iter().zip(&new) {
                assert!((a - b).abs() < 1e-12, "{old:?} vs {new:?}");
            }
        }
    }

    #[test]
    fn one_step_equals_many_steps_for_a_linear_strain_path() {
        // The exponential integrator is exact for E linear in time, so one step of Δt and
        // 64 steps of Δt/64 along the same path in E agree to round-off (both models: the
        // multiplicative model's evolution is linear in (E, E_v)).
        for model in [ViscoModel::Convolution, ViscoModel::Multiplicative] {
            let ve = Viscoelastic::new(model, 2.0, &[(0.7, 0.3), (0.3, 3.0)]).unwrap();
            let n = ve.n_state();
            let e_end = Mat2::new(0.2, 0.05, 0.05, -0.1);
            // A ∇u whose Green strain is t E_end: H = sqrt(I + 2 t E) − I.
            let grad = |t: f64| {
                let c = Mat2::identity() + e_end * (2.0 * t);
                let eig = c.symmetric_eigen();
                eig.eigenvectors
                    * Mat2::from_diagonal(&eig.eigenvalues.map(f64::sqrt))
                    * eig.eigenvectors.transpose()
                    - Mat2::identity()
            };
            let (mut s1, mut tmp) = (vec![0.0; n], vec![0.0; n]);
            let (p1, _) = ve.overstress(&grad(1.0), &vec![0.0; n], 0.8, &mut s1, false);
            let mut s = vec![0.0; n];
            let mut p = Mat2::zeros();
            for k in 1..=64 {
                p = ve
                    .overstress(&grad(k as f64 / 64.0), &s, 0.8 / 64.0, &mut tmp, false)
                    .0;
                s.copy_from_slice(&tmp);
            }
            assert!(
                (p - p1).norm() < 1e-12 * p1.norm(),
                "{model:?}: {p} vs {p1}"
            );
        }
    }

    #[test]
    fn parameter_errors() {
        let c = ViscoModel::Convolution;
        assert_eq!(
            Viscoelastic::new(c, 1.0, &[]),
            Err(ViscoError::TermCount(0))
        );
        assert_eq!(
            Viscoelastic::new(c, 1.0, &[(1.0, 0.0)]),
            Err(ViscoError::BadTerm(0, 1.0, 0.0))
        );
        assert!(Viscoelastic::new(c, -1.0, &[(1.0, 1.0)]).is_err());
        assert!(Viscoelastic::new(c, 1.0, &[(f64::NAN, 1.0)]).is_err());
        assert!(Viscoelastic::new(c, 1.0, &[(1.0, 1.0); 9]).is_err());
        assert_eq!(
            ViscoModel::from_name("multiplicative"),
            Some(ViscoModel::Multiplicative)
        );
        assert_eq!(ViscoModel::from_name("maxwell"), None);
    }

    #[test]
    fn small_strain_models_agree() {
        // Both models linearise to the same overstress (γ/2) k ⋆ 2ε̇.
        let prony = [(0.5, 0.2), (0.5, 2.0)];
        let a = Viscoelastic::new(ViscoModel::Convolution, 4.0, &prony).unwrap();
        let b = Viscoelastic::new(ViscoModel::Multiplicative, 4.0, &prony).unwrap();
        let n = a.n_state();
        let (mut sa, mut sb, mut t) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let mut worst = 0.0_f64;
        for k in 1..=50 {
            let s = k as f64 * 0.1;
            let h = Mat2::new(s.sin(), 0.3 * s.cos(), -0.2 * s, 0.5 * (2.0 * s).sin()) * 1e-7;
            let (pa, _) = a.overstress(&h, &sa, 0.1, &mut t, false);
            sa.copy_from_slice(&t);
            let (pb, _) = b.overstress(&h, &sb, 0.1, &mut t, false);
            sb.copy_from_slice(&t);
            worst = worst.max((pa - pb).norm() / pa.norm());
        }
        assert!(worst < 1e-5, "{worst}");
    }

    /// `∇u` of a uniaxial Green strain `E = e e1⊗e1` (no rotation).
    fn uniaxial(e: f64) -> Mat2 {
        Mat2::new((1.0 + 2.0 * e).sqrt() - 1.0, 0.0, 0.0, 0.0)
    }

    /// Drive one point through `E(t) = amp sin(Ωt) e1⊗e1` in `steps_per_cycle` steps per cycle
    /// for `cycles` cycles; returns per step (t, work of the step, stored energy at its end,
    /// dissipation rate at its end where the model has one).
    fn cycle(
        ve: &Viscoelastic,
        amp: f64,
        omega: f64,
        cycles: usize,
        steps_per_cycle: usize,
    ) -> Vec<(f64, f64, f64, Option<f64>)> {
        let dt = 2.0 * std::f64::consts::PI / omega / steps_per_cycle as f64;
        let mut old = vec![0.0; ve.n_state()];
        let mut new = old.clone();
        let mut out = Vec::new();
        for k in 1..=cycles * steps_per_cycle {
            let t = k as f64 * dt;
            let h = uniaxial(amp * (omega * t).sin());
            ve.overstress(&h, &old, dt, &mut new, false);
            out.push((
                t,
                ve.step_work(&old, &new),
                ve.stored_energy(&new),
                ve.dissipation_rate(&h, &new),
            ));
            old.copy_from_slice(&new);
        }
        out
    }

    /// The energy balance of the overstress against the closed form of a Maxwell element: for
    /// `E = ε sin(Ωt) N` (|N| = 1) one Prony term dissipates `π γ g ε² Ωτ/(1 + Ω²τ²)` per
    /// cycle in the periodic state (the loss modulus), for either model at small strain; at
    /// large strain the multiplicative model's dissipation, work − Δ(stored), equals the time
    /// integral of its dissipation rate and stays non-negative.
    #[test]
    fn dissipation_per_cycle_matches_the_loss_modulus() {
        let (gamma, g, tau) = (300.0, 0.7, 0.02);
        for (model, amp, tol) in [
            (ViscoModel::Convolution, 1e-3, 1e-5),
            (ViscoModel::Convolution, 0.3, 1e-5),
            (ViscoModel::Multiplicative, 1e-4, 1e-3),
        ] {
            let ve = Viscoelastic::new(model, gamma, &[(g, tau)]).unwrap();
            for omega_tau in [0.3, 1.0, 4.0] {
                let omega = omega_tau / tau;
                let n = 4000;
                let cycles = 6 + (8.0 / omega_tau).ceil() as usize; // decay of the start-up
                let steps = cycle(&ve, amp, omega, cycles, n);
                let last = &steps[steps.len() - n..];
                let work: f64 = last.iter().map(|s| s.1).sum();
                let d_stored = last[n - 1].2 - steps[steps.len() - n - 1].2;
                let dissipated = work - d_stored;
                let exact = std::f64::consts::PI * gamma * g * amp * amp * omega_tau
                    / (1.0 + omega_tau * omega_tau);
                let err = (dissipated - exact).abs() / exact;
                eprintln!(
                    "{model:?} ε = {amp}, Ωτ = {omega_tau}: dissipated per cycle {dissipated:.6e}, closed form {exact:.6e}, rel err {err:.1e}"
                );
                assert!(err < tol, "{model:?} ε = {amp}, Ωτ = {omega_tau}: {err:e}");
                // The running balance never goes negative.
                let mut cum = 0.0;
                for s in &steps {
                    cum += s.1;
                    assert!(
                        cum - s.2 >= -1e-9 * exact,
                        "negative dissipation {}",
                        cum - s.2
                    );
                }
            }
        }
        // Large strain, multiplicative: work − Δψ = ∫ D dt (trapezoidal), D ≥ 0.
        let ve = Viscoelastic::new(ViscoModel::Multiplicative, gamma, &[(g, tau)]).unwrap();
        let omega = 1.0 / tau;
        let n = 4000;
        let steps = cycle(&ve, 0.3, omega, 3, n);
        let dt = 2.0 * std::f64::consts::PI / omega / n as f64;
        let mut d_prev = 0.0;
        let (mut work, mut integral) = (0.0, 0.0);
        for s in &steps {
            let d =
                s.3.expect("the multiplicative model has a dissipation rate");
            assert!(d >= 0.0, "{d}");
            integral += 0.5 * (d_prev + d) * dt;
            d_prev = d;
            work += s.1;
        }
        let dissipated = work - steps[steps.len() - 1].2;
        let err = (dissipated - integral).abs() / integral;
        eprintln!("multiplicative ε = 0.3: work − ψ = {dissipated:.6e}, ∫ D dt = {integral:.6e}, rel {err:.1e}");
        assert!(err < 1e-4, "{err:e}");
        // The stored energy is the free energy at the committed strain.
        let h = uniaxial(0.2);
        let mut new = vec![0.0; ve.n_state()];
        ve.overstress(&h, &vec![0.0; ve.n_state()], 0.01, &mut new, false);
        let psi = ve.free_energy(&h, &new).unwrap();
        assert!(
            (ve.stored_energy(&new) - psi).abs() <= 1e-12 * psi.abs(),
            "{psi}"
        );
    }

    /// Random admissible 3D `∇u` with |∇u| up to `scale` and `J ∈ (0.5, 2)`.
    fn random_grad3(rng: &mut SplitMix, scale: f64) -> Mat3 {
        loop {
            let h = Mat3::from_fn(|_, _| scale * (2.0 * rng.next() - 1.0));
            let j = (Mat3::identity() + h).determinant();
            if j > 0.5 && j < 2.0 {
                return h;
            }
        }
    }

    /// A 3D history: a few random steps from the reference.
    fn random_state3(ve: &Viscoelastic, rng: &mut SplitMix) -> Vec<f64> {
        let n = ve.n_state_of::<Mat3>();
        let mut s = vec![0.0; n];
        let mut s1 = vec![0.0; n];
        for _ in 0..3 {
            let h = random_grad3(rng, 0.3);
            ve.overstress(&h, &s, 0.2 * rng.next(), &mut s1, false);
            s.copy_from_slice(&s1);
        }
        s
    }

    #[test]
    fn overstress_3d_tangent_against_finite_differences() {
        let prony = [(0.6, 0.05), (0.3, 1.3), (0.1, 20.0)];
        let mut rng = SplitMix(17);
        for model in [ViscoModel::Convolution, ViscoModel::Multiplicative] {
            let ve = Viscoelastic::new(model, 3.0, &prony).unwrap();
            assert_eq!(ve.n_state_of::<Mat3>(), 6 * 4);
            let mut worst = 0.0_f64;
            for _ in 0..20 {
                let old = random_state3(&ve, &mut rng);
                let h = random_grad3(&mut rng, 0.3);
                let dt = 0.3 * rng.next();
                let n = old.len();
                let (mut new, mut scratch) = (vec![0.0; n], vec![0.0; n]);
                let (p, a) = ve.overstress(&h, &old, dt, &mut new, true);
                let (p2, _) = ve.overstress(&h, &old, dt, &mut scratch, false);
                assert_eq!(p, p2);
                assert_eq!(new, scratch);
                let step = 1e-5;
                let mut a_fd = Tangent3::zeros();
                for kl in 0..9 {
                    let mut e = Mat3::zeros();
                    e[(kl / 3, kl % 3)] = step;
                    let pp = ve.overstress(&(h + e), &old, dt, &mut scratch, false).0;
                    let pm = ve.overstress(&(h - e), &old, dt, &mut scratch, false).0;
                    let dp = (pp - pm) / (2.0 * step);
                    for r in 0..9 {
                        a_fd[(r, kl)] = dp[(r / 3, r % 3)];
                    }
                }
                let err = (a - a_fd).norm() / a.norm();
                assert!(err < 1e-7, "{model:?}: tangent FD {err}");
                worst = worst.max(err);
                if model == ViscoModel::Multiplicative {
                    // P_v = ∂ψ/∂F at the end-of-step internal state, frozen.
                    let mut p_fd = Mat3::zeros();
                    for kl in 0..9 {
                        let mut e = Mat3::zeros();
                        e[(kl / 3, kl % 3)] = step;
                        let wp = ve.free_energy(&(h + e), &new).unwrap();
                        let wm = ve.free_energy(&(h - e), &new).unwrap();
                        p_fd[(kl / 3, kl % 3)] = (wp - wm) / (2.0 * step);
                    }
                    let ep = (p - p_fd).norm() / p.norm().max(1e-3);
                    assert!(ep < 1e-7, "free-energy stress {ep}");
                    assert!(ve.dissipation_rate(&h, &new).unwrap() >= 0.0);
                }
            }
            println!("{model:?}: 3D overstress tangent FD worst {worst:.2e}");
        }
    }

    #[test]
    fn overstress_3d_in_plane_strain_is_the_2d_overstress() {
        // A plane-strain path in 3D: the state stays in-plane (E33 = E13 = E23 = 0, C_v33 = 1)
        // and the in-plane overstress equals the 2D one step after step.
        let prony = [(0.6, 0.05), (0.4, 1.3)];
        let mut rng = SplitMix(5);
        for model in [ViscoModel::Convolution, ViscoModel::Multiplicative] {
            let ve = Viscoelastic::new(model, 3.0, &prony).unwrap();
            let (mut s2, mut s3) = (vec![0.0; ve.n_state()], vec![0.0; ve.n_state_of::<Mat3>()]);
            let (mut n2, mut n3) = (s2.clone(), s3.clone());
            for _ in 0..6 {
                let h = random_grad(&mut rng, 0.3);
                let h3 = embed_plane(&h);
                let dt = 0.2 * rng.next();
                let (p2, a2) = ve.overstress(&h, &s2, dt, &mut n2, true);
                let (p3, a3) = ve.overstress(&h3, &s3, dt, &mut n3, true);
                for i in 0..2 {
                    for j in 0..2 {
                        assert!((p2[(i, j)] - p3[(i, j)]).abs() < 1e-13 * p2.norm().max(1.0));
                        for k in 0..2 {
                            for l in 0..2 {
                                let d = a2[(2 * i + j, 2 * k + l)] - a3[(3 * i + j, 3 * k + l)];
                                assert!(d.abs() < 1e-12 * a2.norm().max(1.0));
                            }
                        }
                    }
                }
                let s_2: Mat2 = ve.state_overstress_of(&n2);
                let s_3: Mat3 = ve.state_overstress_of(&n3);
                assert!((s_2[(0, 1)] - s_3[(0, 1)]).abs() < 1e-13 && s_3[(2, 2)].abs() < 1e-13);
                assert!((ve.stored_energy(&n2) - ve.stored_energy_of::<Mat3>(&n3)).abs() < 1e-13);
                assert!((ve.step_work(&s2, &n2) - ve.step_work_of::<Mat3>(&s3, &n3)).abs() < 1e-13);
                s2.copy_from_slice(&n2);
                s3.copy_from_slice(&n3);
            }
        }
    }

    #[test]
    fn models_agree_in_3d_at_small_strain_and_dissipate() {
        let prony = [(0.7, 0.1), (0.3, 2.0)];
        let conv = Viscoelastic::new(ViscoModel::Convolution, 2.0, &prony).unwrap();
        let mult = Viscoelastic::new(ViscoModel::Multiplicative, 2.0, &prony).unwrap();
        let n = conv.n_state_of::<Mat3>();
        let (mut sc, mut sm) = (vec![0.0; n], vec![0.0; n]);
        let (mut nc, mut nm) = (vec![0.0; n], vec![0.0; n]);
        let shape = Mat3::new(0.3, -0.7, 0.4, 0.9, -0.2, 0.1, 0.5, 0.6, -1.0);
        let mut work = 0.0;
        for step in 0..40 {
            let t = 0.05 * step as f64;
            let h = shape * (1e-7 * (3.0 * t).sin());
            let pc = conv.overstress(&h, &sc, 0.05, &mut nc, false).0;
            let pm = mult.overstress(&h, &sm, 0.05, &mut nm, false).0;
            let scale = pc.norm().max(1e-12);
            assert!((pc - pm).norm() < 1e-5 * scale, "step {step}");
            work += conv.step_work_of::<Mat3>(&sc, &nc);
            sc.copy_from_slice(&nc);
            sm.copy_from_slice(&nm);
        }
        // Work = stored + dissipated, dissipated ≥ 0 (trapezoidal work, so up to O(Δt²)).
        assert!(work - conv.stored_energy_of::<Mat3>(&sc) > -1e-3 * work.abs());
    }
}
