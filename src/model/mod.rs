//! The model layer, one code for every dimension: the solid's cell integrand
//! ([`kernel`], generic in the dimension `D` and the node count `N`: plane strain is `D = 2`,
//! the three-dimensional solid `D = 3`), the three-dimensional solid on hexahedral meshes
//! ([`solid3d`]) and its nonlinear system ([`system3d`]); the plane-strain solid with its
//! contact as one nonlinear system R(x) = 0 under a load factor ([`system`]) and the terms an
//! analysis asks its assembly for ([`terms`]). The solvers of [`crate::solver`] drive both
//! systems alike; the drivers of [`crate::driver`] take them and return typed outcomes, and
//! [`crate::setup`] builds them from a scene without importing any driver.
//!
//! The coefficients an analysis supplies (ω², load factors, the step of a viscoelastic
//! history) are values passed to the
//! integrand ([`kernel::Coefficients`]), not flags written on the model.
//!
//! # Frame
//!
//! The axle is x3, x1 points along the road, x2 up; the road is the plane x2 = −H in the
//! unloaded, uncambered, straight-rolling state; the body spins about +x3 with ω > 0; the
//! wheel's mid-plane is x3 = 0 and its width W. The plane-strain program is the slice x3 = 0 of
//! this frame.

pub mod kernel;
pub mod solid3d;
pub mod steady_history3d;
pub mod steady_visc3d;
pub mod system;
pub mod system3d;
pub mod terms;

pub use kernel::{Coefficients, Inadmissible};
pub use solid3d::{PointValues3D, Solid3D};
pub use system::{SolidSystem, SteadyDampingTangent, DEFAULT_DAMPING_CELL_WEIGHT};
pub use system3d::Solid3DSystem;
pub use terms::{Inertia, Rates, Terms};
