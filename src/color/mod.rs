//! Colour: reflectance and transmittance spectra to colours under CIE D65 as
//! seen by the CIE 1931 2° observer, the wavelength-sampling strategies the
//! baker and tracer choose between, and the colour spaces and difference
//! formula (CIE Lab, CIEDE2000) every error figure is reported in.
//!
//! Conventions: XYZ is normalized so a perfect reflector has Y = 1; linear
//! sRGB has IEC 61966-2-1 primaries and a perfect reflector at (1, 1, 1).

pub mod cie_tables;
mod ciede2000;
mod dual;
mod film;
pub mod gradient;
pub mod refine;
mod sampling;
mod space;

pub use film::{stack_colors, stack_colors_cancellable, FilmColor};
pub use sampling::{Sampling, SpectralIntegrator, White};
pub use space::{
    delta_e2000, delta_e2000_rgb, linear_srgb_to_xyz, linear_to_srgb8, white_xyz, xyz_to_lab,
    xyz_to_linear_srgb,
};
