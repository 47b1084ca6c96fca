//! Drivers: build a model from a scene, run an analysis, collect results.
//!
//! * [`frame`]: what the recorder sees of the model's system
//!   ([`crate::model::SolidSystem`]) at a step.
//! * Static, spinning and indentation load stepping ([`spinning`], [`indentation`]), steady
//!   rolling in the spatial frame ([`steady`]: the system, the press, the torque control;
//!   [`steady_solve`]: the first solve, with the nested iteration of [`steady_nested`], and
//!   [`steady_recovery`] when the direct press fails, reported as
//!   [`steady_report::SolveReports`]), time integration ([`transient`]), the
//!   stick-slip oscillator, critical speeds ([`critical`]) and transient-vs-steady comparison
//!   ([`compare`]).
//! * Three dimensions: static indentation ([`indentation3d`]), spinning ([`spinning3d`]),
//!   steady rolling ([`steady3d`]) and transient rolling ([`transient3d`], the same time loop
//!   and integrators as plane strain through [`transient::Body`]) of
//!   [`crate::model::Solid3DSystem`], run from a scene with `mesh.dimension = 3` by [`run3d`].
//! * The `*_run` files are one mode's whole run (outputs, summary, exit status); they take the
//!   model, options and sinks from [`crate::setup`], and [`crate::app::run`] dispatches to them.
//!   How a run solves (linear solver, Newton, load steps) is decided once when its system is
//!   built ([`crate::solver::SolvePlan`], [`crate::setup::solve_plan`]).
//!   Imports go one way: `app` → `*_run` → the analyses → the model ([`crate::model`]) → physics and solvers.
//! * [`model_problem`]: the adaptive model problems of [`crate::adapt`] (lid-driven cavity with
//!   a moving mesh, convection-dominated heat and Burgers with the two-grid method, the
//!   p-method for Navier–Stokes, the L-shape) run from a scene with `[problem]`.
//! * [`results`]: the typed contents of every mode's `summary.json`, which the `*_run` files
//!   fill and [`crate::driver::results::RunOutcome`] carries in memory.
//!
//! Conventions throughout: forces per unit thickness, ω in rad/s (counter-clockwise > 0), the
//! road at x2 = −H below the hub centre, units as the scene declares them.

pub mod adaptive;
pub mod compare;
pub mod compare3d;
pub mod critical;
pub mod envelope;
pub mod frame;
pub mod indentation;
pub mod indentation3d;
pub mod model_problem;
pub mod relocation;
pub mod resistance;
pub mod results;
pub mod run3d;
pub mod spinning;
pub mod spinning3d;
pub mod steady;
pub mod steady3d;
pub mod steady_nested;
pub mod steady_recovery;
pub mod steady_report;
pub mod steady_run;
pub mod steady_solve;
pub mod stick_slip_run;
pub mod tables;
pub mod transient;
pub mod transient3d;
pub mod transient_run;
