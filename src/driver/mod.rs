//! Drivers: build a model from a scene, run an analysis, collect results.

pub mod compare;
pub mod critical;
pub mod frame;
pub mod indentation;
pub mod spinning;
pub mod steady;
pub mod steady_recovery;
pub mod steady_report;
pub mod steady_run;
pub mod stick_slip_run;
pub mod system;
pub mod tables;
pub mod transient;
pub mod transient_run;

pub use system::SolidSystem;
