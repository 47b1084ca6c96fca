//! Physical models: the finite-strain solid (internal work, θ-referential inertia, body
//! force, Q2/P1 pressure terms) assembled on a mesh.
//!
//! [`solid`] states the residual R(χ; η) = ∫ P : ∇η dV − ω² ∫ ρ0 ∂θχ · ∂θη dV − ∫ b · η dV
//! (+ pressure terms) and its tangent, with ∂θ = t · ∇, t = (−X2, X1), the derivative along
//! reference circles; [`theta_derivative`] the nodal θ-derivatives (along the node rings,
//! [`ring_derivative`], or cell averages on any mesh) that the steady mode's strain-rate
//! damping uses (v = ω ∂θχ). Quantities are in the scene's
//! units, per unit thickness (plane strain).

pub mod equilibrated;
pub mod estimate;
pub mod recovery;
pub mod ring_derivative;
pub mod solid;
pub mod streamline_upwind;
pub mod theta_derivative;
pub mod viscoelastic_steady;

pub use ring_derivative::RingDerivative;
pub use solid::{PointValues, PressureMode, SolidModel, ViscousStep};
pub use theta_derivative::{NodalThetaDerivative, ThetaDerivativeSource};
pub use viscoelastic_steady::SteadyHistory;
