//! Baking an atlas table: the charts [`crate::atlas::search`] chooses for
//! the spec's error target, stored as the table's image.

use super::header::atlas_header;
use super::VALIDATION_SEED;
use crate::atlas::search::{build, Goal, SideRequest};
use crate::atlas::Film;
use crate::color::SpectralIntegrator;
use crate::error::{Error, Result};
use crate::lut::sample::Lut;
use crate::lut::validate::{drawing, validate};
use crate::lut::{BakeSpec, Kind, Resolution, MAX_AXIS_NODES};

/// Bakes `spec` (an error target, rgb) as an atlas table, validated at
/// `spec.validation_points` random points.
pub(super) fn bake_atlas(spec: &BakeSpec, progress: &dyn Fn(&str)) -> Result<Lut> {
    if spec.kind != Kind::Rgb {
        return Err(Error::invalid(
            "kind",
            "a spectral table is baked on a grid (--layout grid)",
        ));
    }
    let Resolution::MaxError(max_abs) = spec.resolution else {
        return Err(Error::invalid(
            "resolution",
            "an atlas needs an error target",
        ));
    };
    let integrator = SpectralIntegrator::with_white(spec.sampling, spec.white);
    let film = Film::new(&spec.stack, spec.layer, integrator)?;
    let goal = Goal {
        max_abs: max_abs.is_finite().then_some(max_abs),
        max_de: spec.max_de,
        half: spec.half,
    };
    let sides = [SideRequest {
        film: &film,
        side: 0,
        cos: spec.cos_theta,
        goal,
    }];
    // The points the table's validation draws, so that the search grows
    // the charts until that validation meets the target.
    let mut draw = drawing(VALIDATION_SEED);
    let points: Vec<[f32; 2]> = (0..spec.validation_points)
        .map(|_| {
            let [t, c, _] = draw([spec.thickness_nm, spec.cos_theta, (0.0, 0.0)]);
            [t, c]
        })
        .collect();
    let built = build(
        &sides,
        spec.thickness_nm,
        MAX_AXIS_NODES,
        &[points],
        progress,
    )?;
    let lossless = film.lossless_white();
    let data: Vec<f32> = match lossless {
        Some(_) => built
            .image
            .data
            .chunks_exact(6)
            .flat_map(|t| t[..3].to_vec())
            .collect(),
        None => built.image.data.clone(),
    };
    let header = atlas_header(spec, film.layer(), &built, lossless);
    let mut lut =
        Lut::from_parts(header, data).map_err(|why| Error::invalid("baked table", why))?;
    if spec.validation_points > 0 {
        let stats = validate(&lut, spec.validation_points, VALIDATION_SEED)?;
        lut.set_validation(stats);
    }
    Ok(lut)
}
