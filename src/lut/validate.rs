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
use crate::stats::{P99Histogram, TableFigures};
use crate::sweep::critical_cos;

/// A table's validation against the solver: its figures over every
/// point, the channel names its per-channel arrays follow, and the same
/// points split by where tables are hard, so a bad corner is not averaged
/// away. The header stores it under the field names and in the order it
/// has had since the first tables ([`Record`]), which old tables are read
/// by too.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(from = "Record")]
pub struct Validation {
    /// Over every point, per channel: the largest, the mean and the
    /// 99th-percentile absolute error (relative to the exact value where
    /// that exceeds 1 in magnitude, as the bake's target:
    /// [`scaled_error`]), the percentile read from a histogram (at most
    /// 0.4 % above the exact order statistic, never above the largest).
    /// CIEDE2000 between the table's and the exact colour: for a spectral
    /// table the colour integrates the table's spectrum with the header's
    /// sampling, and is absent when its wavelength axis does not span that
    /// sampling's wavelengths. The seed of the PCG64 stream that drew the
    /// points (the same table, count and seed reproduce the same figures).
    /// The worst point is where the largest error over channels was.
    pub figures: TableFigures,
    /// The table's channel names, the order of the figures' arrays.
    pub channels: Vec<String>,
    /// The figures over the points in each region of the domain that has
    /// any.
    pub regions: Vec<RegionFigures>,
}

/// The name of [`Validation`] before its figures became a
/// [`TableFigures`].
#[deprecated(note = "renamed `lut::Validation`; its figures are `stats::TableFigures`")]
pub type ErrorStats = Validation;

/// The name of [`RegionFigures`] before it.
#[deprecated(note = "renamed `lut::RegionFigures`")]
pub type RegionStats = RegionFigures;

/// The validation over the points that fall in one region of the table's
/// domain, of each point's largest absolute error over channels (its
/// worst channel, the figure a table's target bounds).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RegionFigures {
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
    /// The largest worst-channel error.
    pub max_abs: f64,
    /// The mean worst-channel error.
    pub mean_abs: f64,
}

/// [`Validation`] as the header writes it: `points, seed, channels,
/// max_abs, mean_abs, p99_abs, max_de2000, mean_de2000, worst_point,
/// regions` (docs/lut-format.md). A rename or reordering here is a format
/// change.
#[derive(Serialize, Deserialize)]
struct Record<V = Vec<f64>, N = Vec<String>, R = Vec<RegionFigures>> {
    points: usize,
    /// Always written by irid; absent only from a record built by hand
    /// without one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    seed: Option<u64>,
    channels: N,
    max_abs: V,
    mean_abs: V,
    p99_abs: V,
    max_de2000: Option<[f64; 2]>,
    mean_de2000: Option<[f64; 2]>,
    worst_point: [f64; 3],
    regions: R,
}

impl Serialize for Validation {
    fn serialize<S: serde::Serializer>(
        &self,
        serializer: S,
    ) -> std::result::Result<S::Ok, S::Error> {
        let f = &self.figures;
        Record::<&[f64], &[String], &[RegionFigures]> {
            points: f.points,
            seed: f.seed,
            channels: &self.channels,
            max_abs: &f.max_abs,
            mean_abs: &f.mean_abs,
            p99_abs: &f.p99_abs,
            max_de2000: f.max_delta_e00,
            mean_de2000: f.mean_delta_e00,
            worst_point: f.worst_point,
            regions: &self.regions,
        }
        .serialize(serializer)
    }
}

impl From<Record> for Validation {
    fn from(r: Record) -> Self {
        Validation {
            figures: TableFigures {
                points: r.points,
                max_abs: r.max_abs,
                p99_abs: r.p99_abs,
                mean_abs: r.mean_abs,
                max_delta_e00: r.max_de2000,
                mean_delta_e00: r.mean_de2000,
                seed: r.seed,
                worst_point: r.worst_point,
            },
            channels: r.channels,
            regions: r.regions,
        }
    }
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
pub fn validate(lut: &Lut, points: usize, seed: u64) -> Result<Validation> {
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
    quantile: Vec<P99Histogram>,
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
            quantile: (0..channels).map(|_| P99Histogram::default()).collect(),
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
    ) -> Validation {
        let n = points as f64;
        let colour = self.de_all && self.de_count > 0;
        let figures = TableFigures {
            points,
            mean_abs: self.sum.iter().map(|s| s / n).collect(),
            p99_abs: self
                .quantile
                .iter()
                .zip(&self.max)
                .map(|(q, &max)| q.p99(points, max))
                .collect(),
            max_abs: self.max,
            max_delta_e00: colour.then_some(self.de_max),
            mean_delta_e00: colour.then(|| self.de_sum.map(|s| s / self.de_count as f64)),
            seed: Some(seed),
            worst_point: self.worst.map_or([0.0; 3], |(_, at)| at),
        };
        let mut stats = Validation {
            figures,
            channels: channels.iter().map(|s| s.to_string()).collect(),
            regions: Vec::new(),
        };
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
                stats.regions.push(RegionFigures {
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

impl Lut {
    /// Records validation figures in the header (written with the table).
    pub fn set_validation(&mut self, stats: Validation) {
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
    use super::{max_or_nan, Validation};

    /// A header's validation record as tables have always stored it (an
    /// rgb table's, and a spectral one's without colour figures) reads
    /// into the shared figures and writes back byte for byte, fields in
    /// their order; and the figures land where they belong.
    #[test]
    fn the_header_record_reads_and_writes_back_unchanged() {
        let rgb = concat!(
            r#"{"points":3,"seed":7,"channels":["reflectance.R","transmittance.R"],"#,
            r#""max_abs":[0.5,0.25],"mean_abs":[0.125,0.0625],"p99_abs":[0.5,0.1875],"#,
            r#""max_de2000":[1.5,2.5],"mean_de2000":[0.75,1.25],"#,
            r#""worst_point":[305.5,0.03125,0.0],"regions":[{"name":"grazing","#,
            r#""description":"incidence beyond 80°","points":2,"max_abs":0.5,"mean_abs":0.375}]}"#
        );
        let spectral = concat!(
            r#"{"points":1,"seed":0,"channels":["reflectance","transmittance"],"#,
            r#""max_abs":[0.00001,0.00002],"mean_abs":[0.00001,0.00002],"p99_abs":[0.00001,0.00002],"#,
            r#""max_de2000":null,"mean_de2000":null,"worst_point":[1.0,0.5,550.0],"regions":[]}"#
        );
        for text in [rgb, spectral] {
            let v: Validation = serde_json::from_str(text).unwrap();
            assert_eq!(serde_json::to_string(&v).unwrap(), text);
        }
        let v: Validation = serde_json::from_str(rgb).unwrap();
        let f = &v.figures;
        assert_eq!((f.points, f.seed), (3, Some(7)));
        assert_eq!(f.max_abs, [0.5, 0.25]);
        assert_eq!(f.mean_abs, [0.125, 0.0625]);
        assert_eq!(f.p99_abs, [0.5, 0.1875]);
        assert_eq!(f.max_delta_e00, Some([1.5, 2.5]));
        assert_eq!(f.mean_delta_e00, Some([0.75, 1.25]));
        assert_eq!(f.worst_point, [305.5, 0.03125, 0.0]);
        assert_eq!(v.channels, ["reflectance.R", "transmittance.R"]);
        assert_eq!((v.regions[0].points, v.regions[0].mean_abs), (2, 0.375));
    }

    #[test]
    fn a_nan_error_is_never_the_smallest() {
        assert_eq!(max_or_nan(&[1e-4, 3e-4, 2e-4]), 3e-4);
        assert_eq!(max_or_nan(&[]), 0.0);
        assert!(max_or_nan(&[1e-4, f64::NAN, 2e-4]).is_nan());
        assert!(max_or_nan(&[f64::NAN, 2e-4]).is_nan());
    }
}
