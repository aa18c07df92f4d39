//! Validation: the table against direct evaluation by the solver at random
//! off-grid points, with the hard angles reported on their own.

use rand::{Rng, SeedableRng};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::sample::{channel_names, Lut};
use super::Kind;
use crate::atlas::search::scaled_error;
use crate::color::refine::Refinement;
use crate::color::{delta_e2000_rgb, Sampling, SpectralIntegrator};
use crate::error::{Error, Result};
use crate::optics::lanes::SpectralWeights;
use crate::optics::{solve_mixed, StackGrid};
use crate::stats::p99_index;
use crate::sweep::critical_cos;

/// Error of a table against the solver. Arrays named `*_abs` have one
/// entry per channel (in `channels` order); `*_de2000` have two entries,
/// the reflectance colour and the transmittance colour.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ErrorStats {
    /// How many random off-grid points were compared with the solver.
    pub points: usize,
    /// Seed of the PCG64 stream that drew the points; the same table,
    /// count and seed reproduce the same figures.
    pub seed: u64,
    /// The table's channel names, the order of every `*_abs` array.
    pub channels: Vec<String>,
    /// Largest absolute error per channel over all points (relative to
    /// the exact value where that exceeds 1 in magnitude, as the bake's
    /// target: [`scaled_error`]).
    pub max_abs: Vec<f64>,
    /// Mean absolute error per channel over all points.
    pub mean_abs: Vec<f64>,
    /// 99th-percentile absolute error per channel (rank ⌈0.99·n⌉), read
    /// from a histogram: at most 0.4 % above the exact order statistic and
    /// never above `max_abs`.
    pub p99_abs: Vec<f64>,
    /// CIEDE2000 between the table's and the exact colour. For a spectral
    /// table the colour integrates the table's spectrum with the header's
    /// sampling; absent when its wavelength axis does not span that
    /// sampling's wavelengths.
    pub max_de2000: Option<[f64; 2]>,
    /// Mean CIEDE2000 over the points, (reflectance, transmittance); absent
    /// exactly when `max_de2000` is.
    pub mean_de2000: Option<[f64; 2]>,
    /// Where the largest error (over channels) occurred: thickness (nm),
    /// cos θ, wavelength (nm; 0 for rgb tables).
    pub worst_point: [f64; 3],
    /// The same points split by where tables are hard, so a bad corner is
    /// not averaged away.
    pub regions: Vec<RegionStats>,
}

/// The validation error over the points that fall in one region of the
/// table's domain. Regions with no points are left out of
/// [`ErrorStats::regions`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RegionStats {
    /// `grazing` (incidence beyond 80°), `critical` (within ±0.02 in cos θ
    /// of the substrate's critical angle) or `other` (everything else); for
    /// an atlas table with an aliased strip or a dispersive critical band
    /// also `aliased` (below the strip's edge), `critical band` (inside the
    /// band) and `resolved` (the rest, where the table's target applies).
    pub name: String,
    /// The region's bounds in words, with the critical cos θ when there is
    /// one.
    pub description: String,
    /// How many of the validation points fell in the region.
    pub points: usize,
    /// Largest absolute error over all channels.
    pub max_abs: f64,
    /// Mean over points of the largest absolute error over channels.
    pub mean_abs: f64,
}

/// cos 80°: beyond it the response changes fastest with angle.
const GRAZING_COS: f64 = 0.173_648_177_666_930_4;
/// Half-width in cos θ of the band around the critical angle.
const CRITICAL_BAND: f64 = 0.02;

struct PointError {
    at: [f64; 3],
    cos_theta: f64,
    abs: [f64; 6],
    de: Option<[f64; 2]>,
}

/// The most validation points: memory no longer grows with the count (see
/// [`CHUNK`]), but at a few microseconds a point this is hours of work.
pub const MAX_POINTS: usize = 100_000_000;

/// Compares the table with the solver at `points` random points spread
/// uniformly over the table's domain (thickness, cos θ and, for spectral
/// tables, wavelength), drawn from a PCG64 stream seeded with `seed`.
pub fn validate(lut: &Lut, points: usize, seed: u64) -> Result<ErrorStats> {
    if !(1..=MAX_POINTS).contains(&points) {
        return Err(Error::invalid(
            "points",
            format!("must be between 1 and {MAX_POINTS}, got {points}"),
        ));
    }
    let h = lut.header();
    let range = |k: usize| {
        let n = &h.axes[k].nodes;
        (n[0], n[n.len() - 1])
    };
    let (t_range, c_range) = (range(0), range(1));
    let w_range = if h.kind == Kind::Spectral {
        range(2)
    } else {
        (0.0, 0.0)
    };
    let checker = PointChecker::new(lut)?;
    let mut draw = drawing(seed);

    let n_channels = channel_names(h.kind).len();

    let critical = critical_cos(&h.stack, h.kind, w_range)
        .filter(|&cc| cc >= c_range.0 - CRITICAL_BAND && cc <= c_range.1 + CRITICAL_BAND);
    let aliased_below = h.atlas.as_ref().map_or(0.0, |t| t.aliased_below_cos);
    let unsought_band = h.atlas.as_ref().and_then(|t| t.critical_band_cos);
    let mut totals = Totals::new(n_channels, critical, aliased_below, unsought_band);
    // Points are drawn and evaluated a chunk at a time and folded into
    // running figures in draw order: memory stays the same for any count,
    // and the figures do not depend on the number of threads.
    let mut chunk: Vec<[f32; 3]> = Vec::with_capacity(CHUNK.min(points));
    let mut done = 0;
    while done < points {
        let take = CHUNK.min(points - done);
        chunk.clear();
        chunk.extend((0..take).map(|_| draw([t_range, c_range, w_range])));
        done += take;
        let errors: Vec<PointError> = chunk
            .par_iter()
            .map_init(
                || checker.scratch(),
                |scratch, &point| checker.check(scratch, point),
            )
            .collect::<Result<_>>()?;
        for e in &errors {
            totals.add(e);
        }
    }
    Ok(totals.finish(points, seed, channel_names(h.kind), critical))
}

/// The validation's random points, one call per point: (thickness, cos θ,
/// wavelength) uniform over the given ranges, from a PCG64 stream seeded
/// with `seed`, as f32 (what the sampler receives).
pub(crate) fn drawing(seed: u64) -> impl FnMut([(f64, f64); 3]) -> [f32; 3] {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    move |ranges| ranges.map(|(lo, hi)| (lo + rng.random::<f64>() * (hi - lo)) as f32)
}

/// What every point's comparison needs: the table, the stack's indices at
/// the colour integration's wavelengths, and the integrator.
struct PointChecker<'a> {
    lut: &'a Lut,
    integrator: SpectralIntegrator,
    /// The integrator's weights laid out for the batched solver.
    weights: SpectralWeights,
    /// The stack at the integration's wavelengths; empty when a spectral
    /// table does not span them (its points then get no colour).
    color_grid: StackGrid,
    color_covered: bool,
    /// Where the film's fringes are narrower than the integration's step,
    /// the exact colour takes more points per nanometre.
    refinement: Refinement,
}

/// One thread's buffers for [`PointChecker::check`].
struct PointScratch {
    thicknesses_nm: Vec<f64>,
    indices: Vec<num_complex::Complex64>,
}

impl<'a> PointChecker<'a> {
    fn new(lut: &'a Lut) -> Result<Self> {
        let h = lut.header();
        let sampling: Sampling = h.color.sampling.parse()?;
        let integrator = SpectralIntegrator::with_white(sampling, h.color.white);
        let color_covered = match h.kind {
            Kind::Rgb => true,
            Kind::Spectral => {
                let w = &h.axes[2].nodes;
                let (lo, hi) = (w[0], w[w.len() - 1]);
                integrator
                    .wavelengths_nm()
                    .iter()
                    .all(|&x| x >= lo && x <= hi)
            }
        };
        let wavelengths: &[f64] = if color_covered {
            integrator.wavelengths_nm()
        } else {
            &[]
        };
        let color_grid = StackGrid::new(&h.stack, wavelengths)?;
        let weights = if color_covered {
            integrator.rgb_lane_weights()
        } else {
            SpectralWeights::new([&[], &[], &[]])
        };
        let layer = (h.layer > 0).then_some(h.layer);
        let refinement = Refinement::new(&h.stack, layer, &integrator)?;
        Ok(PointChecker {
            lut,
            refinement,
            weights,
            integrator,
            color_grid,
            color_covered,
        })
    }

    fn scratch(&self) -> PointScratch {
        PointScratch {
            thicknesses_nm: self.lut.header().stack.thicknesses_nm(),
            indices: Vec::new(),
        }
    }

    /// The exact colour of one point, its whole spectrum solved at once
    /// (eight or four wavelengths per vector) and integrated as it is solved,
    /// compared with the table's: the exact (R, T) colours and their
    /// CIEDE2000 from the table's.
    fn exact_color(
        &self,
        s: &mut PointScratch,
        cos: f64,
        table_r: &[f64; 3],
        table_t: &[f64; 3],
    ) -> Result<([f64; 3], [f64; 3], [f64; 2])> {
        let sums = self.refinement.weighted_spectrum(
            &self.color_grid,
            &self.weights,
            &s.thicknesses_nm,
            cos,
        )?;
        let (r, t) = (sums.reflectance, sums.transmittance);
        let de = [delta_e2000_rgb(*table_r, r), delta_e2000_rgb(*table_t, t)];
        Ok((r, t, de))
    }

    /// The table against the solver at one point (thickness, cos θ,
    /// wavelength; the wavelength is unused for rgb tables).
    fn check(&self, s: &mut PointScratch, [t, c, w]: [f32; 3]) -> Result<PointError> {
        let h = self.lut.header();
        if h.layer > 0 {
            s.thicknesses_nm[h.layer - 1] = f64::from(t);
        }
        let cos = f64::from(c);
        let mut abs = [0.0; 6];
        let de = match h.kind {
            Kind::Rgb => {
                let sample = self.lut.sample_rgb(t, c);
                let table_r = sample.reflectance.map(f64::from);
                let table_t = sample.transmittance.map(f64::from);
                let (r, tr, de) = self.exact_color(s, cos, &table_r, &table_t)?;
                for k in 0..3 {
                    abs[k] = scaled_error(table_r[k], r[k]);
                    abs[3 + k] = scaled_error(table_t[k], tr[k]);
                }
                Some(de)
            }
            Kind::Spectral => {
                h.stack.indices_at(f64::from(w), &mut s.indices)?;
                let resp = solve_mixed(
                    &s.indices,
                    &s.thicknesses_nm,
                    self.color_grid.coherence(),
                    f64::from(w),
                    cos,
                );
                let (r, tr) = self.lut.sample_spectral(t, c, w);
                abs[0] = scaled_error(f64::from(r), resp.r());
                abs[1] = scaled_error(f64::from(tr), resp.t());
                if self.color_covered {
                    Some(self.spectral_color_error(s, t, c)?)
                } else {
                    None
                }
            }
        };
        Ok(PointError {
            at: [f64::from(t), cos, f64::from(w)],
            cos_theta: cos,
            abs,
            de,
        })
    }

    /// CIEDE2000 of a spectral table's colour at (t, c), its spectrum read
    /// at every integration wavelength, against the exact colour.
    fn spectral_color_error(&self, s: &mut PointScratch, t: f32, c: f32) -> Result<[f64; 2]> {
        let wavelengths = self.integrator.wavelengths_nm();
        let mut table_r = vec![0.0; wavelengths.len()];
        let mut table_t = vec![0.0; wavelengths.len()];
        for (k, &wl) in wavelengths.iter().enumerate() {
            let (r, t) = self.lut.sample_spectral(t, c, wl as f32);
            table_r[k] = f64::from(r);
            table_t[k] = f64::from(t);
        }
        let rgb_r = self.integrator.rgb(&table_r);
        let rgb_t = self.integrator.rgb(&table_t);
        Ok(self.exact_color(s, f64::from(c), &rgb_r, &rgb_t)?.2)
    }
}

/// Points evaluated at once: enough to keep every thread busy, few enough
/// that the chunk's errors (about 100 bytes a point) stay small.
const CHUNK: usize = 1 << 16;

/// Running figures over the points seen so far.
struct Totals {
    channels: usize,
    critical: Option<f64>,
    max: Vec<f64>,
    sum: Vec<f64>,
    quantile: Vec<QuantileHistogram>,
    de_all: bool,
    de_max: [f64; 2],
    de_sum: [f64; 2],
    de_count: usize,
    worst: Option<(f64, [f64; 3])>,
    /// cos θ below which an atlas table's colour integration is aliased (0:
    /// nowhere).
    aliased_below: f64,
    /// The cos θ band over which an atlas table's critical angle moves with
    /// the wavelength, where its target is not sought.
    unsought_band: Option<[f64; 2]>,
    /// grazing, critical, other, aliased, critical band, resolved: points,
    /// largest error, sum of errors.
    regions: [(usize, f64, f64); 6],
}

impl Totals {
    fn new(
        channels: usize,
        critical: Option<f64>,
        aliased_below: f64,
        unsought_band: Option<[f64; 2]>,
    ) -> Totals {
        Totals {
            channels,
            critical,
            aliased_below,
            unsought_band,
            max: vec![0.0; channels],
            sum: vec![0.0; channels],
            quantile: (0..channels)
                .map(|_| QuantileHistogram::default())
                .collect(),
            de_all: true,
            de_max: [0.0; 2],
            de_sum: [0.0; 2],
            de_count: 0,
            worst: None,
            regions: [(0, 0.0, 0.0); 6],
        }
    }

    fn add(&mut self, p: &PointError) {
        for ch in 0..self.channels {
            let e = p.abs[ch];
            // total_cmp: a NaN error is the largest, never dropped.
            if e.total_cmp(&self.max[ch]).is_gt() {
                self.max[ch] = e;
            }
            self.sum[ch] += e;
            self.quantile[ch].add(e);
        }
        match p.de {
            Some(d) => {
                for (k, &de) in d.iter().enumerate() {
                    self.de_max[k] = self.de_max[k].max(de);
                    self.de_sum[k] += de;
                }
                self.de_count += 1;
            }
            None => self.de_all = false,
        }
        let w = max_or_nan(&p.abs[..self.channels]);
        // The last of equal maxima, as Iterator::max_by picks.
        if self
            .worst
            .is_none_or(|(best, _)| !w.total_cmp(&best).is_lt())
        {
            self.worst = Some((w, p.at));
        }
        let c = p.cos_theta;
        let near_critical = self
            .critical
            .is_some_and(|cc| (c - cc).abs() < CRITICAL_BAND);
        let mut count = |r: usize| {
            let region = &mut self.regions[r];
            region.0 += 1;
            region.1 = region.1.max(w);
            region.2 += w;
        };
        if c < GRAZING_COS {
            count(0);
        }
        if near_critical {
            count(1);
        }
        if c >= GRAZING_COS && !near_critical {
            count(2);
        }
        if self.aliased_below > 0.0 || self.unsought_band.is_some() {
            let in_band = self.unsought_band.is_some_and(|[a, b]| c >= a && c <= b);
            count(if c < self.aliased_below {
                3
            } else if in_band {
                4
            } else {
                5
            });
        }
    }

    fn finish(
        self,
        points: usize,
        seed: u64,
        channels: &[&str],
        critical: Option<f64>,
    ) -> ErrorStats {
        let n = points as f64;
        let mut stats = ErrorStats {
            points,
            seed,
            channels: channels.iter().map(|s| s.to_string()).collect(),
            mean_abs: self.sum.iter().map(|s| s / n).collect(),
            p99_abs: self
                .quantile
                .iter()
                .zip(&self.max)
                .map(|(q, &max)| q.p99(points, max))
                .collect(),
            max_abs: self.max,
            max_de2000: None,
            mean_de2000: None,
            regions: Vec::new(),
            worst_point: self.worst.map_or([0.0; 3], |(_, at)| at),
        };
        if self.de_all && self.de_count > 0 {
            stats.max_de2000 = Some(self.de_max);
            stats.mean_de2000 = Some(self.de_sum.map(|s| s / self.de_count as f64));
        }
        let descriptions = [
            (
                "grazing",
                "incidence beyond 80° (cos θ < 0.1736)".to_string(),
            ),
            (
                "critical",
                critical.map_or(String::new(), |cc| {
                    format!(
                        "within ±{CRITICAL_BAND} in cos θ of the substrate's critical angle (cos θc = {cc:.6})"
                    )
                }),
            ),
            ("other", "every remaining point".to_string()),
            (
                "aliased",
                format!(
                    "cos θ below {:.6}, where the film's fringes are aliased (narrower than the colour integration, or at one wavelength than a chart follows) and the table's target is not sought",
                    self.aliased_below
                ),
            ),
            (
                "critical band",
                self.unsought_band.map_or(String::new(), |[a, b]| {
                    format!(
                        "cos θ {a:.6} to {b:.6}, over which the critical angle moves with the wavelength and the table's target is not sought"
                    )
                }),
            ),
            (
                "resolved",
                match self.unsought_band {
                    None => format!("cos θ from {:.6} up, where the target applies", self.aliased_below),
                    Some([a, b]) => format!(
                        "cos θ from {:.6} up outside {a:.6} to {b:.6}, where the target applies",
                        self.aliased_below
                    ),
                },
            ),
        ];
        for ((name, description), (count, max, sum)) in descriptions.into_iter().zip(self.regions) {
            if count > 0 {
                stats.regions.push(RegionStats {
                    name: name.into(),
                    description,
                    points: count,
                    max_abs: max,
                    mean_abs: sum / count as f64,
                });
            }
        }
        stats
    }
}

/// Counts of non-negative errors in bins of their f64 bit pattern (the
/// exponent and the top [`QUANTILE_BITS`] bits of the mantissa), so a
/// quantile is found in bounded memory whatever the number of points: a
/// block of counts per binary exponent that occurs (a few dozen in
/// practice, 2 kB each). Adding an error is two indexings, which matters
/// because the errors are added one by one after each parallel chunk.
struct QuantileHistogram {
    /// Indexed by the biased exponent; a block holds its mantissa bins.
    by_exponent: Vec<Option<Box<[u64; 1 << QUANTILE_BITS]>>>,
    /// NaN errors, above every number.
    nan: u64,
}

impl Default for QuantileHistogram {
    fn default() -> Self {
        QuantileHistogram {
            by_exponent: vec![None; 1 << 11],
            nan: 0,
        }
    }
}

/// Mantissa bits kept per bin: a bin spans at most 2⁻⁸ of its values, so
/// a quantile read from the histogram is within 0.4 % of the exact one.
const QUANTILE_BITS: u32 = 8;

impl QuantileHistogram {
    fn add(&mut self, e: f64) {
        if e.is_nan() {
            self.nan += 1;
        } else {
            let bin = Self::bin(e);
            let (exponent, mantissa) = (bin >> QUANTILE_BITS, bin & ((1 << QUANTILE_BITS) - 1));
            let block = self.by_exponent[exponent as usize]
                .get_or_insert_with(|| Box::new([0; 1 << QUANTILE_BITS]));
            block[mantissa as usize] += 1;
        }
    }

    fn bin(e: f64) -> u64 {
        e.abs().to_bits() >> (52 - QUANTILE_BITS)
    }

    /// The 99th percentile of `points` errors whose largest is `max` (the
    /// value of rank ⌈0.99·n⌉ in ascending order): the upper edge of the bin
    /// holding that rank, but never above `max`. Within 0.4 % above the
    /// exact order statistic, and exact when that is the largest error.
    fn p99(&self, points: usize, max: f64) -> f64 {
        let rank = p99_index(points) as u64 + 1;
        let mut seen = 0;
        let bins = self
            .by_exponent
            .iter()
            .enumerate()
            .flat_map(|(exponent, block)| {
                block.iter().flat_map(move |b| {
                    b.iter().enumerate().map(move |(m, &count)| {
                        (((exponent as u64) << QUANTILE_BITS) | m as u64, count)
                    })
                })
            });
        for (bin, count) in bins {
            seen += count;
            if seen >= rank {
                let edge = f64::from_bits((bin + 1) << (52 - QUANTILE_BITS));
                return edge.min(max);
            }
        }
        f64::NAN
    }
}

impl Lut {
    /// Records validation figures in the header (written with the table).
    pub fn set_validation(&mut self, stats: ErrorStats) {
        self.header_mut().error.validation = Some(stats);
    }
}

/// The largest of `values` (0 for none), or NaN if any is NaN: `f64::max`
/// alone drops a NaN, which would let a broken point pass as the best.
pub(crate) fn max_or_nan(values: &[f64]) -> f64 {
    values.iter().fold(0.0f64, |a, &b| {
        if a.is_nan() || b.is_nan() {
            f64::NAN
        } else {
            a.max(b)
        }
    })
}

#[cfg(test)]
mod tests {
    use super::{max_or_nan, QuantileHistogram};

    /// The histogram's p99 against sorting, over errors spread across many
    /// decades, with ties, zeros and a NaN.
    #[test]
    fn histogram_p99_is_within_its_bin_of_the_exact_one() {
        let mut state = 11u64;
        for points in [1usize, 2, 99, 100, 101, 1000, 12_345] {
            let mut h = QuantileHistogram::default();
            let mut all = Vec::new();
            for k in 0..points {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let e = if k % 17 == 0 {
                    0.0
                } else {
                    10f64.powf(-12.0 * (state >> 40) as f64 / (1u64 << 24) as f64)
                };
                h.add(e);
                all.push(e);
            }
            all.sort_by(f64::total_cmp);
            let max = all[points - 1];
            let rank = crate::stats::p99_index(points);
            let exact = all[rank];
            let got = h.p99(points, max);
            assert!(
                got >= exact && got <= exact * (1.0 + 1.0 / 256.0) + f64::MIN_POSITIVE,
                "{points} points: p99 {got:e}, exact {exact:e}"
            );
            if rank == points - 1 {
                assert_eq!(got, max);
            }
        }
        let mut h = QuantileHistogram::default();
        h.add(f64::NAN);
        assert!(h.p99(1, f64::NAN).is_nan());
    }

    #[test]
    fn a_nan_error_is_never_the_smallest() {
        assert_eq!(max_or_nan(&[1e-4, 3e-4, 2e-4]), 3e-4);
        assert_eq!(max_or_nan(&[]), 0.0);
        assert!(max_or_nan(&[1e-4, f64::NAN, 2e-4]).is_nan());
        assert!(max_or_nan(&[f64::NAN, 2e-4]).is_nan());
    }
}
