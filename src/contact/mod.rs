//! Contact of the cylinder's outer surface with the rigid road.
//!
//! Conventions: the road is the line x2 = −H moving with speed v0 along +x1 in the
//! hub frame; penetration δ = (−H − x2)_+ ≥ 0, its rate δ̇ = −ẋ2; slip velocity of the body
//! relative to the road w = ẋ1 − v0. Tractions act on the body per unit **reference** length of
//! the outer boundary: the normal traction t_n ≥ 0 pushes in +x2, the tangential traction
//! t_T = −μ t_n φ_ε(w) opposes slip.
//!
//! * [`laws`]: normal compliance and friction laws with consistent derivatives;
//! * [`facet`]: the contact element on the outer facets (residual, tangent, load control);
//! * [`facet3d`]: the 3D contact element on the quad facets of hexahedral meshes against the
//!   road plane x2 = −H (vector slip, residual and tangent in the cell's dofs, patch samples);
//! * [`steady_slip`]: the steady mode's continuous slip velocity (nodal θ-derivatives);
//! * [`laws_vec`]: the friction laws with a 2D tangential slip vector (3D contact);
//! * [`steady_elastic`]: the steady mode's elastic-slip Coulomb friction (marched return mapping);
//! * [`stick_slip`]: the spring–mass block on a moving belt (paper §4), integrated with diffsol.

pub mod facet;
pub mod facet3d;
pub mod laws;
pub mod laws_vec;
pub mod steady_elastic;
pub mod steady_slip;
pub mod steady_slip3d;
pub mod stick_slip;

pub use facet::{ContactModel, ContactSample, ContactTotals, FacetRule, SlipKinematics};
pub use laws::{
    Bound, Clamp, Friction, FrictionKind, FrictionLaw, FrictionLawSpec, NormalCompliance, ParamSpec,
};
