//! # tread
//!
//! Finite-element simulation of rolling contact of a hyperelastic hollow cylinder in plane
//! strain: a rigid hub, a rubber annulus, a rigid road. See `README.md` for the user's view; the
//! formulation is stated in each module's docs, the conventions here (spatial frame with the hub centre
//! at the origin, x1 right, x2 up, counter-clockwise spin ω > 0; forces per unit thickness;
//! units as the scene declares them).
//!
//! Layout: [`math`] aliases, [`mesh`] structured annulus and mesh data, [`element`] shape
//! functions and quadrature, [`material`] hyperelastic laws, [`assembly`] dofs / pattern /
//! parallel assembler, [`physics`] element kernels, [`solver`] Newton, load stepping and sparse
//! direct solvers, [`driver`] analyses, [`io`] scenes and outputs, [`setup`] scene → model,
//! options and sinks, [`app`] the `tread` program (dispatch on the analysis mode),
//! [`sweep`] parameter sweeps over many runs (local process pool or Slurm job array).

pub mod adapt;
pub mod app;
pub mod assembly;
pub mod contact;
pub mod driver;
pub mod element;
pub mod io;
pub mod material;
pub mod math;
pub mod mesh;
pub mod params;
pub mod physics;
pub mod setup;
pub mod solver;
pub mod sweep;
