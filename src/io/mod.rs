//! Input and output: scene files ([`scene`]), result files ([`output`]), the recorder and its
//! sinks ([`record`]) and log replay ([`replay`]).

pub mod output;
pub mod record;
pub mod reference;
pub mod replay;
pub mod scene;

pub use scene::{Scene, SceneError, SceneErrors};
