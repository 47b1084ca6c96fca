//! Adaptive finite elements on quadtree meshes: the space with hanging-node and
//! degree-transition constraints, the Poisson model problem, a posteriori error estimators,
//! marking, refinement and solution transfer.
//!
//! The adapt loop is five named steps (see [`driver`]): **solve → estimate → mark → refine →
//! transfer**.
//!
//! [`moving_mesh`] adapts by relocating the nodes of a fixed topology instead (r-adaptivity:
//! solve → indicator → relocate → transfer), on the Navier–Stokes cavity with bilinear cells.

pub mod driver;
pub mod estimate;
pub mod moving_mesh;
pub mod navier_stokes;
pub mod poisson;
pub mod quadtree;
pub mod space;
