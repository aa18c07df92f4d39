//! The colour of a whole stack: its reflectance and transmittance spectra at
//! each angle, reduced by one sampling strategy.

use serde::Serialize;

use super::SpectralIntegrator;
use crate::error::{Error, Result};
use crate::optics::{Response, Stack, StackGrid};

/// A stack's reflected and transmitted colour under D65 at one angle.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FilmColor {
    /// Incidence angle in the ambient, degrees from the normal, in [0, 90).
    pub angle_deg: f64,
    /// Linear sRGB of the unpolarized reflectance spectrum, a perfect
    /// reflector being (1, 1, 1) (the integrator's white convention).
    pub reflectance_rgb: [f64; 3],
    /// Linear sRGB of the unpolarized transmittance spectrum (power into
    /// the substrate), on the same scale as `reflectance_rgb`.
    pub transmittance_rgb: [f64; 3],
    /// CIE XYZ, Y = 1 for a perfect reflector.
    pub reflectance_xyz: [f64; 3],
    /// CIE XYZ of the transmittance spectrum, on the scale of
    /// `reflectance_xyz` (Y = 1 for a transmittance of 1 at every
    /// wavelength).
    pub transmittance_xyz: [f64; 3],
}

/// Colours of `stack` at each incidence angle (degrees, in [0, 90)), with
/// unpolarized light from the ambient side. Fails, naming the layer, where
/// an incoherent layer lases.
pub fn stack_colors(
    stack: &Stack,
    integrator: &SpectralIntegrator,
    angles_deg: &[f64],
) -> Result<Vec<FilmColor>> {
    if let Some(a) = angles_deg.iter().find(|a| !(**a >= 0.0 && **a < 90.0)) {
        return Err(Error::invalid(
            "angle",
            format!("{a} is outside [0, 90) degrees"),
        ));
    }
    let grid = StackGrid::new(stack, integrator.wavelengths_nm())?;
    let cos_theta0: Vec<f64> = angles_deg.iter().map(|a| a.to_radians().cos()).collect();
    let samples = integrator.wavelengths_nm().len();
    // Wavelength-major: the response at wavelength i, angle j is [i × angles + j].
    let mut responses = vec![Response::default(); samples * angles_deg.len()];
    grid.solve(&cos_theta0, &mut responses);
    grid.check_solved(&cos_theta0, &responses)?;
    let (mut r, mut t) = (vec![0.0; samples], vec![0.0; samples]);
    Ok(angles_deg
        .iter()
        .enumerate()
        .map(|(j, &angle_deg)| {
            for (i, resp) in responses
                .iter()
                .skip(j)
                .step_by(angles_deg.len())
                .enumerate()
            {
                (r[i], t[i]) = (resp.r(), resp.t());
            }
            FilmColor {
                angle_deg,
                reflectance_rgb: integrator.rgb(&r),
                transmittance_rgb: integrator.rgb(&t),
                reflectance_xyz: integrator.xyz(&r),
                transmittance_xyz: integrator.xyz(&t),
            }
        })
        .collect())
}
