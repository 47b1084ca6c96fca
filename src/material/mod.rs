//! Hyperelastic materials for plane-strain finite strain.
//!
//! # Conventions
//!
//! - Plane strain: `F = I + ∇u` is 2×2 with `F33 = 1`; `J = det F`. The invariants `I1`, `I2` are
//!   those of the 3D right Cauchy–Green tensor `C = FᵀF` (eigenvalues `λ1², λ2², 1`):
//!   `I1 = F:F + 1`, `I2 = F:F + J²` (see [`invariants`]).
//! - `W` is the strain energy per unit reference volume (per unit thickness in 2D); `P = ∂W/∂F` is
//!   the first Piola–Kirchhoff stress and `A = ∂P/∂F` the tangent, flattened row-major as in
//!   [`crate::math`]: `A[(v(i,J), v(k,L))] = ∂P_iJ/∂F_kL`. Every law here is hyperelastic, so
//!   `A` has major symmetry (`A = Aᵀ` as a 4×4 matrix).
//! - Materials take `∇u`, not `F`, and form `I1 − 3`, `I2 − 3`, `J − 1` and `ln J` from it
//!   without cancellation; the stress is then written as `P = s0 I + a ∇u + b cof ∇u` with a
//!   closed-form `s0` (see [`invariants`]), so it keeps full relative precision at tiny strain.
//!   The energy itself is formed naively from these quantities; near `F = I` it is `O(|∇u|²)` and
//!   carries a relative error of about `ε/|∇u|`, enough for line searches and FD checks.
//! - **Inadmissible states.** When `J ≤ 0` (or `J` is `NaN`), `energy` returns `+∞`, and `stress`
//!   and `stress_tangent` return matrices filled with `+∞` — never `NaN`, never a panic. A residual
//!   assembled from such a point is non-finite, which is what the Newton line search tests.
//!
//! # Laws
//!
//! | type | `W` | small-strain shear `G` | bulk `K` (3D) |
//! |---|---|---|---|
//! | [`NeoHookean`] `{mu, lambda}` | `μ/2 (I1 − 3) − μ ln J + λ/2 (ln J)²` | `μ` | `λ + 2μ/3` |
//! | [`MooneyRivlin`] `{c1, c2, kappa}` | `c1 (Ī1 − 3) + c2 (Ī2 − 3) + κ/2 (J − 1)²` | `2(c1 + c2)` | `κ` |
//! | [`MooneyRivlinIncompressible`] `{c1, c2}` | `c1 (I1 − 3) + c2 (I2 − 3)`, with `J = 1` imposed by the element | `2(c1 + c2)` | — |
//! | [`Yeoh`] `{c10, c20, c30, kappa}` | `c10 x + c20 x² + c30 x³ + κ/2 (J − 1)²`, `x = Ī1 − 3` | `2 c10` | `κ` |
//!
//! with `Ī1 = J^(−2/3) I1`, `Ī2 = J^(−4/3) I2`. The plane-strain small-strain limit of a
//! compressible law is `σ = λ tr(ε) I + 2G ε` with `λ = K − 2G/3`.
//!
//! [`Material`] is the closed set of laws used by the element kernels (static dispatch by
//! `match`); [`fd_check`] holds the finite-difference checker every law passes.
//!
//! # Scene description and registration
//!
//! Each law declares, next to its physics, how a scene file gives it ([`MaterialLawSpec`]): its
//! `model` keyword, its parameters ([`ParamSpec`]: key, meaning, unit, bound), how to build it
//! from their values, its small-strain moduli and any check between parameters. The one list in
//! `materials!` builds from these entries both [`Material`] with its dispatch and the keyword
//! enum [`MaterialKind`]; the scene's `[material]` keys, reference, range checks and messages
//! are made from the declarations. Adding a law is its file with its [`Hyperelastic`] and
//! [`MaterialLawSpec`] impls, its `mod` line, and its name in that list.
//!
//! # State
//!
//! [`Constitutive`] is the material interface with state in and state out: the committed
//! history of a quadrature point, the step `Δt` and the end-of-step `∇u` go in; the end-of-step
//! stress, its algorithmic tangent and the new history come out. Every [`Hyperelastic`] law is
//! a `Constitutive` with no state (`n_state() = 0`, `Δt` ignored), so elastic materials carry
//! no history and pay nothing. [`viscoelastic`] holds the stateful laws (a hyperelastic law
//! plus a Prony-series overstress).

pub mod fd_check;
pub mod incompressible;
pub mod invariants;
pub mod mooney_rivlin;
pub mod neo_hookean;
#[cfg(test)]
mod tests_3d;
pub mod viscoelastic;
pub mod viscoelastic_ring;
pub mod yeoh;

pub use fd_check::{check_material, check_stateful, tangent_asymmetry, FdReport, SplitMix};
pub use incompressible::{pressure_stress_tangent, MooneyRivlinIncompressible};
pub use invariants::{dcof_df, InvariantDerivs, InvariantTensor, Kinematics};
pub use mooney_rivlin::MooneyRivlin;
pub use neo_hookean::NeoHookean;
pub use viscoelastic::{ViscoModel, Viscoelastic, ViscoelasticMaterial};
pub use yeoh::Yeoh;

use crate::math::{Mat2, Tangent, Tensor};
pub use crate::params::{Bound, LawKind, ParamSpec};

/// A hyperelastic law evaluated from the displacement gradient, in the dimension of `T`
/// (`Mat2`: plane strain, the default; `Mat3`: three dimensions; see [`crate::math::Tensor`]).
pub trait Hyperelastic<T: Tensor = Mat2>: Send + Sync {
    /// Strain energy per unit reference volume W(F), F = I + grad_u (in plane strain
    /// 2×2 with F33 = 1). +inf if J <= 0.
    fn energy(&self, grad_u: &T) -> f64;
    /// First Piola–Kirchhoff stress P = dW/dF.
    fn stress(&self, grad_u: &T) -> T;
    /// P and the tangent A = dP/dF (flattening of math.rs).
    fn stress_tangent(&self, grad_u: &T) -> (T, T::Tangent);
}

/// A material with state in and state out (see the module docs).
pub trait Constitutive: Send + Sync {
    /// History values per quadrature point (0: no history).
    fn n_state(&self) -> usize;
    /// End-of-step first Piola–Kirchhoff stress at `grad_u`, from the committed state `old` over
    /// a step `dt ≥ 0`, and with `with_tangent` the algorithmic tangent `∂P/∂F` (zeros
    /// otherwise). The new state is written to `new` (`old` and `new` have `n_state()` values).
    /// `dt = 0` at the committed `grad_u` returns the committed stress and state.
    fn update(
        &self,
        grad_u: &Mat2,
        old: &[f64],
        dt: f64,
        new: &mut [f64],
        with_tangent: bool,
    ) -> (Mat2, Tangent);
    /// Helmholtz free energy per unit reference volume at `grad_u` with the internal state
    /// frozen at `state`, if the law has one (then `P = ∂ψ/∂F` at fixed state).
    fn free_energy(&self, grad_u: &Mat2, state: &[f64]) -> Option<f64>;
}

impl<M: Hyperelastic> Constitutive for M {
    #[inline]
    fn n_state(&self) -> usize {
        0
    }
    #[inline]
    fn update(
        &self,
        grad_u: &Mat2,
        _old: &[f64],
        _dt: f64,
        _new: &mut [f64],
        with_tangent: bool,
    ) -> (Mat2, Tangent) {
        if with_tangent {
            self.stress_tangent(grad_u)
        } else {
            (self.stress(grad_u), Tangent::zeros())
        }
    }
    fn free_energy(&self, grad_u: &Mat2, _state: &[f64]) -> Option<f64> {
        Some(self.energy(grad_u))
    }
}

/// How a scene file gives a hyperelastic law, declared next to its physics: its `model`
/// keyword, its parameters (key, meaning, unit, bound; see [`ParamSpec`]), how to build it from
/// their values and its small-strain moduli. Registering the type in `materials!` adds it to
/// [`Material`] (with its dispatch) and to the scene's `[material] model` keywords, keys,
/// checks and reference.
pub trait MaterialLawSpec: Hyperelastic + Copy {
    /// Keyword of `[material] model` (snake_case).
    const NAME: &'static str;
    /// One line on the law for the scene reference.
    const SUMMARY: &'static str;
    /// Parameters, in the order of [`Self::from_values`] and [`Self::values`] (the density
    /// `rho` is every material's and is not listed).
    const PARAMS: &'static [ParamSpec];
    /// Whether the element must impose `J = 1` with a pressure field. The scene then also
    /// takes `formulation` (`exact` or `perturbed`) and, for `perturbed`, an optional `kappa`.
    const INCOMPRESSIBLE: bool = false;

    /// The law from its parameter values in the order of [`Self::PARAMS`] (not range-checked).
    fn from_values(v: &[f64]) -> Self;

    /// The parameter values in the order of [`Self::PARAMS`].
    fn values(&self) -> Vec<f64>;

    /// Shear modulus `G` of the small-strain limit.
    fn shear_modulus(&self) -> f64;

    /// 3D bulk modulus `K` of the small-strain limit (`None` for an incompressible law).
    fn bulk_modulus(&self) -> Option<f64>;

    /// Out-of-plane Cauchy stress σ33 of plane strain from this law alone (an element pressure
    /// field adds `−p`); NaN when `J ≤ 0`.
    fn cauchy_33(&self, grad_u: &Mat2) -> f64;

    /// Checks between parameters beyond their own bounds, on the values a scene gives (any may
    /// be missing): `(key, message)` for each violation.
    fn cross_check(_given: &dyn Fn(&str) -> Option<f64>) -> Vec<(&'static str, String)> {
        Vec::new()
    }
}

/// The one list of materials: the [`Material`] enum with its dispatch by `match` and the
/// keyword enum [`MaterialKind`] of `[material] model`, from the laws' [`MaterialLawSpec`]s.
macro_rules! materials {
    ($($law:ident),+ $(,)?) => {
        /// The closed set of hyperelastic laws, dispatched by `match` in hot loops (scene
        /// `model =` is each law's [`MaterialLawSpec::NAME`], its keys the law's
        /// [`MaterialLawSpec::PARAMS`]).
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub enum Material {
            $(
                #[doc = concat!("See [`", stringify!($law), "`].")]
                $law($law),
            )+
        }

        /// Which material law, without its parameters: the keyword of `[material] model`.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        pub enum MaterialKind {
            $(
                #[doc = concat!("[`", stringify!($law), "`].")]
                $law,
            )+
        }

        impl MaterialKind {
            /// Every kind, in registration order.
            pub const ALL: &'static [MaterialKind] = &[$(MaterialKind::$law),+];
            /// The scene keyword of every kind, in the order of [`Self::ALL`].
            pub const NAMES: &'static [&'static str] = &[$(<$law as MaterialLawSpec>::NAME),+];

            /// The scene keyword of this kind.
            pub fn as_str(self) -> &'static str {
                match self {
                    $(MaterialKind::$law => <$law as MaterialLawSpec>::NAME,)+
                }
            }

            /// One line on the law (see [`MaterialLawSpec::SUMMARY`]).
            pub fn summary(self) -> &'static str {
                match self {
                    $(MaterialKind::$law => <$law as MaterialLawSpec>::SUMMARY,)+
                }
            }

            /// The parameters of this kind, in their declared order.
            pub fn params(self) -> &'static [ParamSpec] {
                match self {
                    $(MaterialKind::$law => <$law as MaterialLawSpec>::PARAMS,)+
                }
            }

            /// Whether the law needs a pressure field (see [`MaterialLawSpec::INCOMPRESSIBLE`]).
            pub fn is_incompressible(self) -> bool {
                match self {
                    $(MaterialKind::$law => <$law as MaterialLawSpec>::INCOMPRESSIBLE,)+
                }
            }

            /// The law's checks between parameters (see [`MaterialLawSpec::cross_check`]).
            pub fn cross_check(
                self,
                given: &dyn Fn(&str) -> Option<f64>,
            ) -> Vec<(&'static str, String)> {
                match self {
                    $(MaterialKind::$law => <$law as MaterialLawSpec>::cross_check(given),)+
                }
            }

            /// The law of this kind from its parameter values, in the order of [`Self::params`].
            ///
            /// # Panics
            /// If `values` is shorter than [`Self::params`].
            pub fn build(self, values: &[f64]) -> Material {
                match self {
                    $(MaterialKind::$law => Material::$law(<$law as MaterialLawSpec>::from_values(values)),)+
                }
            }
        }

        impl Material {
            /// Which law this is.
            pub fn kind(&self) -> MaterialKind {
                match self {
                    $(Material::$law(_) => MaterialKind::$law,)+
                }
            }

            /// The parameter values, in the order of [`MaterialKind::params`].
            pub fn values(&self) -> Vec<f64> {
                match self {
                    $(Material::$law(m) => m.values(),)+
                }
            }

            /// Shear modulus `G` of the small-strain limit.
            pub fn small_strain_shear_modulus(&self) -> f64 {
                match self {
                    $(Material::$law(m) => m.shear_modulus(),)+
                }
            }

            /// 3D bulk modulus `K` of the small-strain limit (`None` for an incompressible law).
            pub fn small_strain_bulk_modulus(&self) -> Option<f64> {
                match self {
                    $(Material::$law(m) => m.bulk_modulus(),)+
                }
            }

            /// Out-of-plane Cauchy stress σ33 of plane strain from this law alone (an element
            /// pressure field adds `−p`); NaN when `J ≤ 0`.
            pub fn cauchy_33(&self, grad_u: &Mat2) -> f64 {
                match self {
                    $(Material::$law(m) => m.cauchy_33(grad_u),)+
                }
            }
        }

        impl<T: InvariantTensor> Hyperelastic<T> for Material {
            #[inline]
            fn energy(&self, grad_u: &T) -> f64 {
                match self {
                    $(Material::$law(m) => m.energy(grad_u),)+
                }
            }

            #[inline]
            fn stress(&self, grad_u: &T) -> T {
                match self {
                    $(Material::$law(m) => m.stress(grad_u),)+
                }
            }

            #[inline]
            fn stress_tangent(&self, grad_u: &T) -> (T, T::Tangent) {
                match self {
                    $(Material::$law(m) => m.stress_tangent(grad_u),)+
                }
            }
        }

        $(
            impl From<$law> for Material {
                fn from(m: $law) -> Self {
                    Material::$law(m)
                }
            }
        )+
    };
}

materials!(NeoHookean, MooneyRivlin, MooneyRivlinIncompressible, Yeoh);

impl Material {
    /// Whether the element must impose `J = 1` with a pressure field.
    pub fn is_incompressible(&self) -> bool {
        self.kind().is_incompressible()
    }

    /// The scene-file name of the law.
    pub fn name(&self) -> &'static str {
        self.kind().as_str()
    }

    /// The value of the parameter `key`, if the law has one.
    pub fn param(&self, key: &str) -> Option<f64> {
        let i = self.kind().params().iter().position(|p| p.key == key)?;
        self.values().get(i).copied()
    }

    /// Give the parameter `key` the value `value`; false (and no change) if the law has no
    /// such parameter. Used by the steady solver's homotopies (e.g. in the bulk modulus).
    pub fn set_param(&mut self, key: &str, value: f64) -> bool {
        let kind = self.kind();
        let Some(i) = kind.params().iter().position(|p| p.key == key) else {
            return false;
        };
        let mut values = self.values();
        values[i] = value;
        *self = kind.build(&values);
        true
    }
}

impl LawKind for MaterialKind {
    type Law = Material;
    const WHAT: &'static str = "material model";

    fn kinds() -> &'static [Self] {
        Self::ALL
    }
    fn keyword(self) -> &'static str {
        self.as_str()
    }
    fn declared(self) -> &'static [ParamSpec] {
        self.params()
    }
    fn build_law(self, values: &[f64]) -> Material {
        self.build(values)
    }
}

crate::params::law_kind_impls!(MaterialKind);

/// Property checks shared by the tests of every law.
#[cfg(test)]
pub(crate) mod test_util {
    use super::*;
    use crate::math::{flatten, v};

    /// Moderate strains: shear, compression, expansion, rotation, with `J ∈ [0.6, 1.6]`.
    pub fn sample_grads() -> Vec<Mat2> {
        let stretch_rot = rotation(0.7) * Mat2::new(1.2, 0.0, 0.0, 0.8) - Mat2::identity();
        let shear_rot = rotation(-2.5) * Mat2::new(1.0, 0.6, 0.0, 1.0) - Mat2::identity();
        vec![
            Mat2::new(0.0, 0.3, 0.0, 0.0),    // simple shear, J = 1
            Mat2::new(0.1, 0.2, -0.05, 0.15), // general, J = 1.275
            Mat2::new(-0.3, 0.05, 0.1, -0.1), // biaxial compression, J = 0.625
            Mat2::new(0.25, -0.1, 0.2, 0.2),  // expansion, J = 1.52
            Mat2::new(-0.35, 0.0, 0.0, 0.0),  // uniaxial compression, J = 0.65
            Mat2::new(-0.2, 0.5, 0.1, 0.05),  // shear + compression, J = 0.79
            Mat2::new(0.4, 0.0, 0.0, -0.3),   // isochoric-ish stretch, J = 0.98
            stretch_rot,                      // rotated stretch, J = 0.96
            shear_rot,                        // large rotation + shear, J = 1
            rotation(1.0) - Mat2::identity(), // pure rotation (stress-free if compressible)
        ]
    }

    pub fn rotation(theta: f64) -> Mat2 {
        let (s, c) = theta.sin_cos();
        Mat2::new(c, -s, s, c)
    }

    #[test]
    fn samples_cover_the_requested_range() {
        let js: Vec<f64> = sample_grads()
            .iter()
            .map(|g| (Mat2::identity() + g).determinant())
            .collect();
        assert!(js.iter().all(|j| (0.6..=1.6).contains(j)), "{js:?}");
        assert!(js.iter().any(|j| *j < 0.7) && js.iter().any(|j| *j > 1.5));
    }

    /// FD check at every sample; returns the worst (stress, tangent) errors.
    pub fn assert_fd_consistent<M: Hyperelastic>(m: &M) -> (f64, f64) {
        let mut worst = (0.0_f64, 0.0_f64);
        for g in sample_grads() {
            let r = check_material(m, &g);
            assert!(r.stress_rel_err < 1e-6, "stress FD at {g}: {r:?}");
            assert!(r.tangent_rel_err < 1e-6, "tangent FD at {g}: {r:?}");
            worst = (
                worst.0.max(r.stress_rel_err),
                worst.1.max(r.tangent_rel_err),
            );
        }
        worst
    }

    /// Major symmetry of the tangent at every sample and at the reference; returns the worst.
    pub fn assert_tangent_symmetric<M: Hyperelastic>(m: &M) -> f64 {
        let mut worst = 0.0_f64;
        for g in sample_grads().into_iter().chain([Mat2::zeros()]) {
            let asym = tangent_asymmetry(&m.stress_tangent(&g).1);
            assert!(asym < 1e-12, "asymmetry {asym} at {g}");
            worst = worst.max(asym);
        }
        worst
    }

    /// `W(QF) = W(F)`, `P(QF) = Q P(F)`, `A(QF)_iJkL = Q_ia Q_kb A(F)_aJbL`; returns the worst
    /// relative error. Energy and stress are measured against `max(|W|, |A||∇u|²)` and
    /// `max(|P|, |A||∇u|)`, so that a stress-free rotated state compares against its strain
    /// scale rather than against rounding noise.
    pub fn assert_objective<M: Hyperelastic>(m: &M) -> f64 {
        let mut worst = 0.0_f64;
        for g in sample_grads() {
            let f = Mat2::identity() + g;
            let (w, (p, a)) = (m.energy(&g), m.stress_tangent(&g));
            let (a_norm, g_norm) = (a.norm(), g.norm());
            // R[v(i,J), v(a,K)] = Q_ia δ_JK rotates the first index of each pair.
            let rotate = |q: &Mat2| {
                let mut r = Tangent::zeros();
                for i in 0..2 {
                    for k in 0..2 {
                        for jj in 0..2 {
                            r[(v(i, jj), v(k, jj))] = q[(i, k)];
                        }
                    }
                }
                r
            };
            for theta in [0.3, -1.2, 2.9] {
                let q = rotation(theta);
                let gq = q * f - Mat2::identity();
                let (wq, (pq, aq)) = (m.energy(&gq), m.stress_tangent(&gq));
                let r = rotate(&q);
                let ew = (wq - w).abs() / w.abs().max(a_norm * g_norm * g_norm);
                let ep = (pq - q * p).norm() / p.norm().max(a_norm * g_norm);
                let ea = (aq - r * a * r.transpose()).norm() / a_norm;
                assert!(ew < 1e-12, "energy objectivity {ew} at {g}, θ = {theta}");
                assert!(ep < 1e-12, "stress objectivity {ep} at {g}, θ = {theta}");
                assert!(ea < 1e-12, "tangent objectivity {ea} at {g}, θ = {theta}");
                worst = worst.max(ew).max(ep).max(ea);
            }
        }
        worst
    }

    /// `J ≤ 0`: energy `+∞`, stress and tangent without `NaN`, no panic.
    pub fn assert_inadmissible_safe<M: Hyperelastic>(m: &M) {
        for g in [
            Mat2::new(-1.0, 0.0, 0.0, 0.0),         // J = 0
            Mat2::new(-1.0, 0.3, 0.0, -1.0),        // F = [[0, .3], [0, 0]], J = 0
            Mat2::new(-2.0, 0.0, 0.0, 0.0),         // reflection, J = −1
            Mat2::new(-1.0, 1.0, 1.0, -1.0),        // F = [[0,1],[1,0]], J = −1
            Mat2::new(-1.0 - 1e-12, 0.0, 0.0, 0.0), // J ≈ −1e-12
            Mat2::new(-1.5, 0.2, -0.4, 3.0),        // J < 0, generic
        ] {
            assert_eq!(m.energy(&g), f64::INFINITY, "energy at {g}");
            let p = m.stress(&g);
            let (p2, a) = m.stress_tangent(&g);
            assert!(!p.iter().any(|x| x.is_nan()), "NaN stress at {g}");
            assert!(!p2.iter().any(|x| x.is_nan()), "NaN stress at {g}");
            assert!(!a.iter().any(|x| x.is_nan()), "NaN tangent at {g}");
        }
    }

    /// Plane-strain linear elasticity `σ = λ tr(ε) I + 2μ ε`.
    pub fn linear_stress(h: &Mat2, lambda: f64, mu: f64) -> Mat2 {
        let eps = (h + h.transpose()) * 0.5;
        Mat2::identity() * (lambda * eps.trace()) + eps * (2.0 * mu)
    }

    /// `A_iJkL = λ δ_iJ δ_kL + μ (δ_ik δ_JL + δ_iL δ_Jk)`.
    pub fn linear_tangent(lambda: f64, mu: f64) -> Tangent {
        let i = flatten(&Mat2::identity());
        let mut t = i * i.transpose() * lambda + Tangent::identity() * mu;
        for a in 0..2 {
            for b in 0..2 {
                t[(v(a, b), v(b, a))] += mu;
            }
        }
        t
    }

    /// Small-strain limit of a compressible law: `P(∇u) → σ_lin(∇u)` and `A(0) = A_lin`.
    /// At `|∇u| ~ 1e-12` a cancelling implementation would be wrong by ~1e-4 relative.
    /// Returns the relative errors at the scales 1e-8 and 1e-12.
    pub fn assert_small_strain_linear<M: Hyperelastic>(m: &M, lambda: f64, mu: f64) -> [f64; 2] {
        assert_eq!(m.stress(&Mat2::zeros()), Mat2::zeros());
        assert_eq!(m.stress_tangent(&Mat2::zeros()).0, Mat2::zeros());
        assert_eq!(m.energy(&Mat2::zeros()), 0.0);
        let a0 = m.stress_tangent(&Mat2::zeros()).1;
        let al = linear_tangent(lambda, mu);
        assert!(
            (a0 - al).norm() < 1e-12 * al.norm(),
            "A(0) = {a0}, expected {al}"
        );

        let shapes = [
            Mat2::new(0.3, -0.7, 0.4, 0.9),
            Mat2::new(0.0, 1.0, 0.0, 0.0),
            Mat2::new(-1.0, 0.2, 0.5, -0.6),
        ];
        let mut worst = [0.0_f64; 2];
        for (w, (scale, tol)) in worst.iter_mut().zip([(1e-8, 1e-6), (1e-12, 1e-9)]) {
            for s in shapes {
                let g = s * scale;
                let lin = linear_stress(&g, lambda, mu);
                for p in [m.stress(&g), m.stress_tangent(&g).0] {
                    let e = (p - lin).norm() / lin.norm();
                    assert!(
                        e < tol,
                        "small strain {scale}: rel err {e}, P = {p}, σ = {lin}"
                    );
                    *w = w.max(e);
                }
            }
        }
        worst
    }
}

#[cfg(test)]
mod tests {
    use super::test_util::*;
    use super::*;

    fn all() -> [Material; 3] {
        [
            NeoHookean::new(1.5, 4.0).into(),
            MooneyRivlin::new(80.0, 20.0, 2000.0).into(),
            MooneyRivlinIncompressible::new(80.0, 20.0).into(),
        ]
    }

    /// Every registered law with parameters `1, 1.5, 2, …` (admissible for every bound above
    /// or at 0): what a newly registered law is checked with, without a test of its own.
    fn registered() -> Vec<Material> {
        MaterialKind::ALL
            .iter()
            .map(|k| {
                let values: Vec<f64> = (0..k.params().len())
                    .map(|i| 1.0 + 0.5 * i as f64)
                    .collect();
                for (p, v) in k.params().iter().zip(&values) {
                    assert!(p.bound.admits(*v), "{k}: {} = {v}", p.key);
                }
                k.build(&values)
            })
            .collect()
    }

    #[test]
    fn every_registered_law_passes_the_material_checks() {
        for m in registered() {
            let (es, et) = assert_fd_consistent(&m);
            let asym = assert_tangent_symmetric(&m);
            let obj = assert_objective(&m);
            assert_inadmissible_safe(&m);
            // Small-strain moduli as declared: ∂P12/∂F12 = G, and K = λ + 2G/3 with the
            // plane-strain λ = ∂P11/∂F22 where the law is compressible.
            let a = m.stress_tangent(&Mat2::zeros()).1;
            let g = m.small_strain_shear_modulus();
            assert!((a[(1, 1)] - g).abs() < 1e-12 * g, "{m:?}");
            match m.small_strain_bulk_modulus() {
                Some(k) => {
                    assert!(!m.is_incompressible(), "{m:?}");
                    assert!((a[(0, 3)] + 2.0 / 3.0 * g - k).abs() < 1e-12 * k, "{m:?}");
                    // A compressible law is stress free at F = I.
                    assert_eq!(m.stress(&Mat2::zeros()), Mat2::zeros(), "{m:?}");
                }
                None => assert!(m.is_incompressible(), "{m:?}"),
            }
            println!(
                "{}: fd stress {es:.2e}, fd tangent {et:.2e}, asym {asym:.2e}, obj {obj:.2e}",
                m.name()
            );
        }
    }

    #[test]
    fn material_declarations_are_consistent() {
        // Keywords are distinct, and a key shared by several laws is declared the same by all.
        let mut names = MaterialKind::NAMES.to_vec();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), MaterialKind::ALL.len());
        for key in MaterialKind::all_keys() {
            assert_ne!(
                key, "rho",
                "the density is every material's, not a law parameter"
            );
            let first = MaterialKind::param(key).copied();
            for kind in MaterialKind::laws_with(key) {
                let p = kind.params().iter().find(|p| p.key == key).copied();
                assert_eq!(p, first, "`{key}` of {kind}");
            }
        }
        // Values go through build/values/param unchanged, in the declared order.
        for kind in MaterialKind::ALL.iter().copied() {
            let values: Vec<f64> = (1..=kind.params().len()).map(|i| 0.5 + i as f64).collect();
            let mut law = kind.build(&values);
            assert_eq!(law.kind(), kind);
            assert_eq!(law.values(), values, "{kind}");
            assert_eq!(kind.as_str().parse::<MaterialKind>(), Ok(kind));
            for (p, v) in kind.params().iter().zip(&values) {
                assert_eq!(law.param(p.key), Some(*v));
                assert!(law.set_param(p.key, 2.0 * v));
                assert_eq!(law.param(p.key), Some(2.0 * v));
            }
            assert!(!law.set_param("no_such_key", 1.0));
        }
        let err = "rubber".parse::<MaterialKind>().unwrap_err();
        assert!(err.contains("\"neo_hookean\""), "{err}");
    }

    #[test]
    fn enum_dispatch_matches_direct_calls() {
        let nh = NeoHookean::new(1.5, 4.0);
        let mr = MooneyRivlin::new(80.0, 20.0, 2000.0);
        let mri = MooneyRivlinIncompressible::new(80.0, 20.0);
        for g in sample_grads() {
            assert_eq!(Material::from(nh).energy(&g), nh.energy(&g));
            assert_eq!(Material::from(mr).stress(&g), mr.stress(&g));
            assert_eq!(
                Material::from(mri).stress_tangent(&g),
                mri.stress_tangent(&g)
            );
        }
    }

    #[test]
    fn enum_passes_all_checks() {
        for m in all() {
            let (es, et) = assert_fd_consistent(&m);
            let asym = assert_tangent_symmetric(&m);
            let obj = assert_objective(&m);
            assert_inadmissible_safe(&m);
            println!(
                "{m:?}: fd stress {es:.2e}, fd tangent {et:.2e}, asym {asym:.2e}, obj {obj:.2e}"
            );
        }
    }

    #[test]
    fn moduli_match_tangent_at_reference() {
        for m in all() {
            let a = m.stress_tangent(&Mat2::zeros()).1;
            let g = m.small_strain_shear_modulus();
            // Shear entry ∂P12/∂F12 = G for every law, incompressible included (its pressure
            // term −p ∂cof/∂F has no (12, 12) entry).
            assert!((a[(1, 1)] - g).abs() < 1e-12 * g, "{m:?}");
            match m.small_strain_bulk_modulus() {
                Some(k) => {
                    assert!(!m.is_incompressible());
                    // Plane-strain λ = ∂P11/∂F22; K = λ + 2G/3.
                    let k_tangent = a[(0, 3)] + 2.0 / 3.0 * g;
                    assert!((k_tangent - k).abs() < 1e-12 * k, "{m:?}");
                }
                None => assert!(m.is_incompressible()),
            }
        }
        assert_eq!(all().map(|m| m.is_incompressible()), [false, false, true]);
        assert_eq!(all()[1].small_strain_shear_modulus(), 200.0);
    }
}
