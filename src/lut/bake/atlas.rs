//! Baking an atlas table: the charts [`crate::atlas::search`] chooses for
//! the spec's error target, stored as the table's image.

use super::header::atlas_header;
use super::VALIDATION_SEED;
use crate::atlas::search::{build, Goal, SideRequest};
use crate::atlas::spectrum::{self, Spacing};
use crate::atlas::{Film, Image};
use crate::color::SpectralIntegrator;
use crate::error::{Error, Result};
use crate::lut::sample::Lut;
use crate::lut::validate::{drawing, validate};
use crate::lut::{BakeSpec, Kind, Resolution, MAX_AXIS_NODES};
use crate::sweep::Side;

/// The share of a spectral table's error target its wavelength
/// interpolation takes; the charts' two axes share the rest.
const WAVELENGTH_SHARE: f64 = 1.0 / 3.0;

/// Bakes `spec` (an error target) as an atlas table, validated at
/// `spec.validation_points` random points.
pub(super) fn bake_atlas(spec: &BakeSpec, progress: &dyn Fn(&str)) -> Result<Lut> {
    let Resolution::MaxError(max_abs) = spec.resolution else {
        return Err(Error::invalid(
            "resolution",
            "an atlas needs an error target",
        ));
    };
    let plan = match spec.kind {
        Kind::Rgb => {
            let integrator = SpectralIntegrator::with_white(spec.sampling, spec.white);
            let goal = Goal {
                max_abs: max_abs.is_finite().then_some(max_abs),
                max_de: spec.max_de,
                half: spec.half,
            };
            FilmPlan {
                film: Film::new(&spec.stack, spec.layer, integrator)?,
                goal,
                wavelengths: vec![],
                charted: spec.thickness_nm,
            }
        }
        Kind::Spectral => {
            // A lasing pole, named before the wavelength probe meets it.
            let integrator = SpectralIntegrator::with_white(spec.sampling, spec.white);
            Film::new(&spec.stack, spec.layer, integrator)?
                .check_lasing(spec.thickness_nm, spec.cos_theta)?;
            spectral_film(spec, max_abs, progress)?
        }
    };
    let FilmPlan {
        film,
        goal,
        wavelengths,
        charted,
    } = plan;
    film.check_lasing(charted, spec.cos_theta)?;
    let sides = [SideRequest {
        film: &film,
        side: Side::Front,
        cos: spec.cos_theta,
        goal,
    }];
    // The points the table's validation draws, so that the search grows
    // the charts until that validation meets the target.
    let mut draw = drawing(VALIDATION_SEED);
    let points: Vec<[f32; 2]> = (0..spec.validation_points)
        .map(|_| {
            let [t, c, _] = draw([charted, spec.cos_theta, (0.0, 0.0)]);
            [t, c]
        })
        .collect();
    let built = build(&sides, charted, MAX_AXIS_NODES, &[points], progress)?;
    let lossless = film.lossless_white();
    let data: Vec<f32> = match lossless {
        _ if film.is_spectral() => wavelength_blocks(&built.image),
        Some(_) => built
            .image
            .data
            .chunks_exact(6)
            .flat_map(|t| t[..3].to_vec())
            .collect(),
        None => built.image.data.clone(),
    };
    let header = atlas_header(spec, film.layer(), &built, lossless, &wavelengths);
    let mut lut =
        Lut::from_parts(header, data).map_err(|why| Error::invalid("baked table", why))?;
    if spec.validation_points > 0 {
        let stats = validate(&lut, spec.validation_points, VALIDATION_SEED)?;
        lut.set_validation(stats);
    }
    Ok(lut)
}

/// A spectral film for `spec`: its wavelength nodes (uniform in
/// wavenumber, as many as [`crate::atlas::spectrum`] measures their
/// interpolation to need, from the cos θ where its fringes are followed
/// up), the charts' share of `max_abs`, and the thickness range the
/// charts cover (the table's, widened by the ratio of neighbouring
/// wavelength nodes at which a lookup reads them).
fn spectral_film(spec: &BakeSpec, max_abs: f64, progress: &dyn Fn(&str)) -> Result<FilmPlan> {
    let range = spec.wavelength_nm;
    let probe = Film::spectral(&spec.stack, spec.layer, &[range.0, range.1], 0.0)?;
    let floor = spectrum::fringe_floor(&probe, range, spec.thickness_nm, spec.cos_theta, max_abs)?;
    let axis = spectrum::choose(
        &spec.stack,
        spec.layer,
        range,
        spec.thickness_nm,
        spec.cos_theta,
        floor,
        WAVELENGTH_SHARE * max_abs,
        Spacing::Wavenumber,
    )?;
    progress(&format!(
        "wavelength: {} nodes uniform in wavenumber over {}–{} nm, largest interpolation error {:.2e} at the probe; fringes aliased below cos θ {floor:.4}",
        axis.nodes_nm.len(),
        range.0,
        range.1,
        axis.measured,
    ));
    let film = Film::spectral(&spec.stack, spec.layer, &axis.nodes_nm, floor)?;
    // The charts take what the wavelength interpolation leaves, keeping a
    // margin over what the probe measured.
    let charts = (max_abs - (1.5 * axis.measured).max(0.1 * max_abs))
        .max((1.0 - WAVELENGTH_SHARE) * max_abs);
    let goal = Goal {
        max_abs: Some(charts),
        max_de: None,
        half: spec.half,
    };
    let ratio = spectrum::largest_ratio(&axis.nodes_nm);
    let (d0, d1) = spec.thickness_nm;
    let widened = (d0 / ratio, d1 * ratio);
    Ok(FilmPlan {
        film,
        goal,
        wavelengths: axis.nodes_nm,
        charted: widened,
    })
}

/// What an atlas bake evaluates: the film, what its charts must meet,
/// a spectral film's wavelength nodes (else none) and the thickness range
/// its charts cover.
struct FilmPlan {
    film: Film,
    goal: Goal,
    wavelengths: Vec<f64>,
    charted: (f64, f64),
}

/// A spectral atlas image (per texel R at each wavelength node, then T)
/// as the table stores it: one block of the atlas's rows per wavelength,
/// each texel (R, T).
fn wavelength_blocks(image: &Image) -> Vec<f32> {
    let w = image.channels / 2;
    let mut out = Vec::with_capacity(image.data.len());
    for k in 0..w {
        for texel in image.data.chunks_exact(image.channels) {
            out.push(texel[k]);
            out.push(texel[w + k]);
        }
    }
    out
}
