//! The slices against irid's rough reflectance at random points (the
//! sampler's own, or the points of a reference computed once).

use super::*;

/// Random cosines of the measurement below [`GRAZING_COS`].
pub(super) const GRAZING_AXIS_POINTS: usize = 6;

/// The slices against [`rough_reflectance`] (see [`measure_sampler`]).
pub(super) fn measure(
    stack: &Stack,
    layer: usize,
    integrator: &SpectralIntegrator,
    slices: &RoughSlices,
) -> Result<(RoughFigures, RoughFigures)> {
    measure_sampler(
        stack,
        layer,
        integrator,
        (slices.atlas.thickness_nm, cos_span(&slices.atlas)),
        MEASURE_SEED,
        &|d, c, r| slices.sample(d, c, r),
    )
}

/// The cos θ range the side-0 charts of `atlas` serve (a corner from 0).
pub fn cos_span(atlas: &Atlas) -> (f64, f64) {
    atlas
        .charts
        .iter()
        .filter(|c| c.side == Side::Front)
        .map(|c| match c.coords {
            Coords::Band { c, .. } => (c.lo, c.hi),
            Coords::Corner { radius, .. } => (0.0, radius.min(1.0)),
        })
        .fold((1.0f64, 0.0f64), |(lo, hi), (a, b)| (lo.min(a), hi.max(b)))
}

/// `sample` (F_eff at thickness nm, cos θ, roughness) against
/// [`rough_reflectance`] of the film `stack` (layer `layer` varying) at
/// every combination of [`MEASURE_THICKNESSES`] random thicknesses and
/// [`MEASURE_AXIS_POINTS`] random cosines (≥ [`GRAZING_COS`]) and
/// roughnesses, over `domain` (the thickness and the cos θ range), drawn
/// from the PCG64 stream of `seed`; then with [`GRAZING_AXIS_POINTS`]
/// cosines below [`GRAZING_COS`] where the range reaches there.
pub fn measure_sampler(
    stack: &Stack,
    layer: usize,
    integrator: &SpectralIntegrator,
    domain: ((f64, f64), (f64, f64)),
    seed: u64,
    sample: &(dyn Fn(f64, f64, f64) -> [f64; 3] + Sync),
) -> Result<(RoughFigures, RoughFigures)> {
    let points = MeasurePoints::draw(
        domain,
        seed,
        [
            MEASURE_THICKNESSES,
            MEASURE_AXIS_POINTS,
            GRAZING_AXIS_POINTS,
        ],
    );
    if points.all_cos().is_empty() {
        return Ok((RoughFigures::default(), RoughFigures::default()));
    }
    let reference = Reference::new(stack, layer, integrator, &points)?;
    Ok(reference.errors(sample))
}

/// Random points of a rough measurement: every combination of the
/// thicknesses, the cosines (at or above [`GRAZING_COS`], then below) and
/// the roughnesses; as f64, or as f32 where they are what a shader gets.
#[derive(Clone, Debug, PartialEq)]
pub struct MeasurePoints<T = f64> {
    /// Thicknesses (nm), ascending, distinct.
    pub thickness: Vec<T>,
    /// cos θ at or above [`GRAZING_COS`], ascending.
    pub cos: Vec<T>,
    /// cos θ below [`GRAZING_COS`], ascending.
    pub grazing_cos: Vec<T>,
    /// Roughnesses, ascending.
    pub roughness: Vec<T>,
}

impl<T: Copy> MeasurePoints<T> {
    /// Every cosine: `cos`, then `grazing_cos`.
    pub fn all_cos(&self) -> Vec<T> {
        self.cos.iter().chain(&self.grazing_cos).copied().collect()
    }
}

impl MeasurePoints {
    /// `[thicknesses, cosines and roughnesses, grazing cosines]` values
    /// uniform over `domain` (thickness nm, cos θ), roughness over [0, 1],
    /// from the PCG64 stream of `seed`, drawn in the order thicknesses,
    /// cosines, roughnesses, grazing cosines; no cosines at or above [`GRAZING_COS`] when the range
    /// stays below it, none below when it stays above.
    pub fn draw(domain: ((f64, f64), (f64, f64)), seed: u64, counts: [usize; 3]) -> MeasurePoints {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        let ((t0, t1), (c0, c1)) = domain;
        let [n_thickness, n_axis, n_grazing] = counts;
        let mut draw = |lo: f64, hi: f64, n: usize| -> Vec<f64> {
            let mut v: Vec<f64> = (0..n)
                .map(|_| lo + rng.random::<f64>() * (hi - lo))
                .collect();
            v.sort_by(f64::total_cmp);
            v.dedup();
            v
        };
        let thickness = draw(t0, t1, n_thickness);
        let cos = if c1 > GRAZING_COS {
            draw(c0.max(GRAZING_COS), c1, n_axis)
        } else {
            Vec::new()
        };
        let roughness = draw(0.0, 1.0, n_axis);
        let grazing_cos = if c0 < GRAZING_COS {
            draw(c0, c1.min(GRAZING_COS), n_grazing)
        } else {
            Vec::new()
        };
        MeasurePoints {
            thickness,
            cos,
            grazing_cos,
            roughness,
        }
    }
}

/// F_eff from [`rough_reflectance`] (default quadrature) at every point of
/// a [`MeasurePoints`]: what slices and the textures made of them are
/// measured against, computed once.
#[derive(Clone, Debug)]
pub struct Reference {
    /// The points' axes and F_eff at each (`cos_theta`: the points'
    /// [`MeasurePoints::all_cos`]).
    pub exact: RoughTable,
    /// How many of `exact.cos_theta` are at or above [`GRAZING_COS`].
    pub main_cos: usize,
}

impl Reference {
    /// F_eff of the film `stack` (layer `layer` varying) at `points`.
    pub fn new(
        stack: &Stack,
        layer: usize,
        integrator: &SpectralIntegrator,
        points: &MeasurePoints,
    ) -> Result<Reference> {
        let exact = rough_reflectance(
            stack,
            layer,
            integrator,
            &points.thickness,
            &points.all_cos(),
            &points.roughness,
            &Quadrature::default(),
        )?;
        Ok(Reference {
            exact,
            main_cos: points.cos.len(),
        })
    }

    /// `sample` (F_eff at thickness nm, cos θ, roughness) against the
    /// reference: over the cosines at or above [`GRAZING_COS`], and over
    /// those below (no points when there are none).
    pub fn errors(
        &self,
        sample: &(dyn Fn(f64, f64, f64) -> [f64; 3] + Sync),
    ) -> (RoughFigures, RoughFigures) {
        let e = &self.exact;
        let errors_over = |cs: std::ops::Range<usize>| -> RoughFigures {
            let errors: Vec<([f64; 3], f64, [f64; 3])> = e
                .roughness
                .par_iter()
                .enumerate()
                .flat_map_iter(|(r, &rv)| {
                    cs.clone().flat_map(move |c| {
                        e.thickness_nm.iter().enumerate().map(move |(t, &tv)| {
                            let cv = e.cos_theta[c];
                            let want = e.at(t, c, r);
                            let got = sample(tv, cv, rv);
                            let abs = std::array::from_fn(|k| (got[k] - want[k]).abs());
                            (abs, delta_e2000_rgb(got, want), [tv, cv, rv])
                        })
                    })
                })
                .collect();
            summarize(&errors)
        };
        (
            errors_over(0..self.main_cos),
            errors_over(self.main_cos..e.cos_theta.len()),
        )
    }
}

/// The figures of per-point errors (absolute error per channel, ΔE00,
/// the point): a NaN (a lookup gone wrong) counts as the worst.
pub(crate) fn summarize(errors: &[([f64; 3], f64, [f64; 3])]) -> RoughFigures {
    if errors.is_empty() {
        return RoughFigures::default();
    }
    let finite = |x: f64| if x.is_nan() { f64::INFINITY } else { x };
    let abs: Vec<f64> = errors.iter().flat_map(|x| x.0.map(finite)).collect();
    let de: Vec<f64> = errors.iter().map(|x| finite(x.1)).collect();
    let s = stats::summarize(&abs, 3, &de, 1);
    let three = |v: &[f64]| -> [f64; 3] { [v[0], v[1], v[2]] };
    RoughFigures {
        points: s.points,
        max_abs: three(&s.max_abs),
        p99_abs: three(&s.p99_abs),
        mean_abs: three(&s.mean_abs),
        max_delta_e00: s.max_de[0],
        mean_delta_e00: s.mean_de[0],
        seed: None,
        worst_point: errors[s.worst.unwrap_or(0)].2,
    }
}
