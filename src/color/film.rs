//! The colour of a whole stack: its reflectance and transmittance spectra at
//! each angle, reduced by one sampling strategy.

use serde::Serialize;

use super::refine::Refinement;
use super::SpectralIntegrator;
use crate::cancel::Cancel;
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
    stack_colors_cancellable(stack, integrator, angles_deg, Cancel::never())
}

/// Work of one block of [`stack_colors_cancellable`] between two looks at
/// its flag, in wavelengths × angles × media: a few milliseconds.
const BLOCK_WORK: usize = 1 << 20;

/// [`stack_colors`], stopping with [`Error::Cancelled`] once `cancel` is
/// set: it solves the angles in blocks of a few milliseconds and looks at
/// the flag before each block and each angle integrated again. Each
/// angle's colour is the same whatever block it falls in.
pub fn stack_colors_cancellable(
    stack: &Stack,
    integrator: &SpectralIntegrator,
    angles_deg: &[f64],
    cancel: &Cancel,
) -> Result<Vec<FilmColor>> {
    if let Some(a) = angles_deg.iter().find(|a| !(**a >= 0.0 && **a < 90.0)) {
        return Err(Error::invalid(
            "angle",
            format!("{a} is outside [0, 90) degrees"),
        ));
    }
    let grid = StackGrid::new(stack, integrator.wavelengths_nm())?;
    let samples = integrator.wavelengths_nm().len();
    let block = (BLOCK_WORK / (samples * (stack.layers.len() + 2)).max(1)).max(1);
    // Angles where some layer's fringes are narrower than the sampling
    // step are integrated again with the points per step they need.
    let refinement = Refinement::new_cancellable(stack, None, integrator, cancel)?;
    let mut colours = Vec::with_capacity(angles_deg.len());
    let mut responses = Vec::new();
    for angles in angles_deg.chunks(block) {
        cancel.check()?;
        let cos_theta0: Vec<f64> = angles.iter().map(|a| a.to_radians().cos()).collect();
        // Wavelength-major: the response at wavelength i, angle j is [i × angles + j].
        responses.clear();
        responses.resize(samples * angles.len(), Response::default());
        grid.solve(&cos_theta0, &mut responses);
        grid.check_solved(&cos_theta0, &responses)?;
        for (j, &angle_deg) in angles.iter().enumerate() {
            let m = refinement.sub_steps(0.0, cos_theta0[j]);
            let ((r, t), by) = if m > 1 {
                cancel.check()?;
                let level = refinement.level(m)?;
                let mut refined = vec![Response::default(); level.grid.wavelengths_nm().len()];
                level.grid.solve(&cos_theta0[j..=j], &mut refined);
                level.grid.check_solved(&cos_theta0[j..=j], &refined)?;
                (powers(&refined, 0, 1), &level.integrator)
            } else {
                (powers(&responses, j, angles.len()), integrator)
            };
            colours.push(FilmColor {
                angle_deg,
                reflectance_rgb: by.rgb(&r),
                transmittance_rgb: by.rgb(&t),
                reflectance_xyz: by.xyz(&r),
                transmittance_xyz: by.xyz(&t),
            });
        }
    }
    Ok(colours)
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
