pub mod fourier_modes;
pub mod reference;
