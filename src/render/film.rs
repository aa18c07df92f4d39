//! The one interface through which the tracer shades thin films. Two
//! implementations: [`super::lut_film::LutFilm`] samples baked tables and
//! [`DirectFilm`] evaluates the transfer matrix at every hit (the reference),
//! so the two modes share every other line of the renderer.

/// Linear-sRGB reflectance and transmittance of a film at one point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FilmRgb {
    pub reflectance: [f32; 3],
    pub transmittance: [f32; 3],
}

/// Which side of the film the light arrives from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Side {
    /// From the ambient: the stack as written.
    Front,
    /// From the substrate (inside a coated gem): the reversed stack, whose
    /// denser incidence medium gives total internal reflection.
    Back,
}

/// Reflectance and transmittance of a film, as linear-sRGB weights under D65.
pub trait FilmShading: Sync + Send {
    /// `cos_theta` is the cosine of the incidence angle in the medium the
    /// light arrives from; `thickness_nm` the varying layer's thickness.
    fn shade(&self, thickness_nm: f32, cos_theta: f32, side: Side) -> FilmRgb;
}
