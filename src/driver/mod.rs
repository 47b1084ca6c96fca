//! Drivers: build a model from a scene, run an analysis, collect results.

pub mod spinning;
pub mod system;

pub use system::SolidSystem;
