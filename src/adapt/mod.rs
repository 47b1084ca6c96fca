//! Adaptive finite elements on quadtree meshes: the space with hanging-node and
//! degree-transition constraints, the Poisson model problem, a posteriori error estimators,
//! marking, refinement and solution transfer.
//!
//! The adapt loop is five named steps (see [`driver`]): **solve → estimate → mark → refine →
//! transfer**. [`marking`] holds what every adapt loop shares (the quadtree ones here and the
//! solid's, [`crate::driver::adaptive`]): the per-cell estimate, the estimator interface and
//! the marking.
//!
//! [`moving_mesh`] adapts by relocating the nodes of a fixed topology instead (r-adaptivity:
//! solve → indicator → relocate → transfer), on the Navier–Stokes cavity with bilinear cells.
//! Transient problems ([`two_grid`]): Crank–Nicolson steps solved by Newton, with an adaptive
//! h-method that estimates the error as the difference between the solutions on the current
//! mesh and on its uniform refinement, refining and coarsening between steps; applied to
//! convection-dominated heat conduction with SUPG ([`convection`]) and to the vector Burgers
//! equations ([`burgers`]). [`p_navier_stokes`] is a p-method for Navier–Stokes on a fixed
//! quadtree (per-cell Q_p/Q_{p−1} pairs, estimate by enrichment, degrees raised before a step
//! is accepted).

pub mod burgers;
pub mod cavity_reference;
pub mod convection;
pub mod driver;
pub mod estimate;
pub mod marking;
pub mod moving_mesh;
pub mod navier_stokes;
pub mod p_navier_stokes;
pub mod poisson;
pub mod quadtree;
pub mod space;
pub mod two_grid;
