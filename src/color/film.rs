//! The colour of a whole stack: its reflectance and transmittance spectra at
//! each angle, reduced by one sampling strategy.

use serde::Serialize;

use super::refine::Refinement;
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
    // Angles where some layer's fringes are narrower than the sampling
    // step are integrated again with the points per step they need.
    let refinement = Refinement::new(stack, None, integrator)?;
    angles_deg
        .iter()
        .enumerate()
        .map(|(j, &angle_deg)| {
            let m = refinement.sub_steps(0.0, cos_theta0[j]);
            let ((r, t), by) = if m > 1 {
                let level = refinement.level(m)?;
                let mut refined = vec![Response::default(); level.grid.wavelengths_nm().len()];
                level.grid.solve(&cos_theta0[j..=j], &mut refined);
                level.grid.check_solved(&cos_theta0[j..=j], &refined)?;
                (powers(&refined, 0, 1), &level.integrator)
            } else {
                (powers(&responses, j, angles_deg.len()), integrator)
            };
            Ok(FilmColor {
                angle_deg,
                reflectance_rgb: by.rgb(&r),
                transmittance_rgb: by.rgb(&t),
                reflectance_xyz: by.xyz(&r),
                transmittance_xyz: by.xyz(&t),
            })
        })
        .collect()
}

/// R and T spectra of the angle at `offset` among `angles` in
/// wavelength-major `responses`.
fn powers(responses: &[Response], offset: usize, angles: usize) -> (Vec<f64>, Vec<f64>) {
    responses
        .iter()
        .skip(offset)
        .step_by(angles)
        .map(|resp| (resp.r(), resp.t()))
        .unzip()
}
