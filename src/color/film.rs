//! The colour of a whole stack: its reflectance and transmittance spectra at
//! each angle, reduced by one sampling strategy.

use serde::Serialize;

use super::SpectralIntegrator;
use crate::error::{Error, Result};
use crate::optics::{solve, Stack};

/// A stack's reflected and transmitted colour under D65 at one angle.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FilmColour {
    pub angle_deg: f64,
    /// Linear sRGB.
    pub reflectance_rgb: [f64; 3],
    pub transmittance_rgb: [f64; 3],
    /// CIE XYZ, Y = 1 for a perfect reflector.
    pub reflectance_xyz: [f64; 3],
    pub transmittance_xyz: [f64; 3],
}

/// Colours of `stack` at each incidence angle (degrees, in [0, 90)), with
/// unpolarized light from the ambient side.
pub fn stack_colours(
    stack: &Stack,
    integrator: &SpectralIntegrator,
    angles_deg: &[f64],
) -> Result<Vec<FilmColour>> {
    stack.validate()?;
    if let Some(a) = angles_deg.iter().find(|a| !(**a >= 0.0 && **a < 90.0)) {
        return Err(Error::invalid(
            "angle",
            format!("{a} is outside [0, 90) degrees"),
        ));
    }
    let wavelengths = integrator.wavelengths_nm();
    // Indices depend on wavelength only: look them up once, not per angle.
    let mut indices = Vec::with_capacity(wavelengths.len());
    for &l in wavelengths {
        let mut n = Vec::new();
        stack.indices_at(l, &mut n)?;
        indices.push(n);
    }
    let thicknesses_nm = stack.thicknesses_nm();
    let (mut r, mut t) = (vec![0.0; wavelengths.len()], vec![0.0; wavelengths.len()]);
    Ok(angles_deg
        .iter()
        .map(|&angle_deg| {
            let cos_theta0 = angle_deg.to_radians().cos();
            for (i, (&l, n)) in wavelengths.iter().zip(&indices).enumerate() {
                let resp = solve(n, &thicknesses_nm, l, cos_theta0);
                (r[i], t[i]) = (resp.r(), resp.t());
            }
            FilmColour {
                angle_deg,
                reflectance_rgb: integrator.rgb(&r),
                transmittance_rgb: integrator.rgb(&t),
                reflectance_xyz: integrator.xyz(&r),
                transmittance_xyz: integrator.xyz(&t),
            }
        })
        .collect())
}
