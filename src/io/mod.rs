//! Input and output: scene files ([`scene`]) and result files ([`output`]).

pub mod output;
pub mod scene;

pub use scene::{Scene, SceneError, SceneErrors};
