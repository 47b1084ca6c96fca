// The Botella & Peyret reference of the cavity at Re = 1000 (tables in
// `tread::adapt::cavity_reference`), shared by tests/cavity.rs and the cavity tools (included,
// not a module).
#[allow(unused_imports)]
use tread::adapt::cavity_reference::{BP_PSI_MIN, BP_U, BP_V, BP_X, BP_Y};
