//! Physical models: the finite-strain solid (internal work, θ-referential inertia, body
//! force, Q2/P1 pressure terms) assembled on a mesh.

pub mod ring_derivative;
pub mod solid;
pub mod viscoelastic_steady;

pub use ring_derivative::RingDerivative;
pub use solid::{PointValues, PressureMode, SolidModel};
pub use viscoelastic_steady::SteadyHistory;
