//! Error figures: how far what a reader computes (a table read by its
//! sampler, an atlas read as a GPU reads it, a rough table's slices, an
//! export through its textures) is from the exact values, over a set of
//! points. One type, [`Figures`], whose array shapes follow what is
//! measured ([`TableFigures`] for a table's validation, [`ColourFigures`]
//! for the six colour channels of a smooth film, [`RoughFigures`] for
//! F_eff's three, [`AtlasFigures`] for any channel count); one summary of
//! per-point errors, [`summarize`], and its streaming counterpart for
//! counts too large to sort, `P99Histogram`; and one percentile rule,
//! [`p99_index`], that both follow. A table's validation
//! (`lut::Validation`) is a [`TableFigures`] with its channel names and
//! regions, written into the table's header under the field names it has
//! always had.

use serde::{Deserialize, Serialize};

/// The 0-based index, among `n` errors in ascending order, of the one
/// reported as the 99th percentile: rank ⌈0.99·n⌉ (1-based), at least the
/// first (0 when there are none).
pub fn p99_index(n: usize) -> usize {
    ((n as f64 * 0.99).ceil() as usize).clamp(1, n.max(1)) - 1
}

/// Error figures over `points` points: per channel (`A`: one entry per
/// channel) the largest, the 99th-percentile and the mean absolute error,
/// per colour (`D`) the largest and mean CIEDE2000, and where the largest
/// error over channels was (`P`). The serialized field names are what
/// film.json and the rough table's header state.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Figures<A, D, P> {
    /// Points measured.
    pub points: usize,
    /// Largest absolute error per channel.
    pub max_abs: A,
    /// 99th percentile of the absolute error per channel ([`p99_index`]).
    pub p99_abs: A,
    /// Mean absolute error per channel.
    pub mean_abs: A,
    /// Largest CIEDE2000, per colour.
    pub max_delta_e00: D,
    /// Mean CIEDE2000, per colour.
    pub mean_delta_e00: D,
    /// The PCG64 seed of the points, when they were drawn at random for
    /// this measurement alone (film.json states it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// Where the largest absolute error over channels was.
    pub worst_point: P,
}

/// A smooth colour film read through an export: R.r, R.g, R.b, T.r, T.g,
/// T.b; the reflected and the transmitted colour; (thickness nm, cos θ).
pub type ColourFigures = Figures<[f64; 6], [f64; 2], [f64; 2]>;

/// A rough film's F_eff: its R, G, B; its colour; (thickness nm, cos θ,
/// roughness).
pub type RoughFigures = Figures<[f64; 3], f64, [f64; 3]>;

/// An atlas of any film: its channels (six for a colour film, R and T at
/// each wavelength node for a spectral one); the reflected and the
/// transmitted colour (zero for a spectral film); (thickness nm, cos θ).
pub type AtlasFigures = Figures<Vec<f64>, [f64; 2], [f64; 2]>;

/// A table against the solver (`lut::validate`): its channels (R.r … T.b,
/// or R and T of a spectral table); the reflected and the transmitted
/// colour, absent when a spectral table's wavelengths do not span the
/// colour integration; (thickness nm, cos θ, wavelength nm or 0 for an rgb
/// table).
pub type TableFigures = Figures<Vec<f64>, Option<[f64; 2]>, [f64; 3]>;

impl<A: AsRef<[f64]>, D, P> Figures<A, D, P> {
    /// The largest of `max_abs`.
    pub fn max_all(&self) -> f64 {
        self.max_abs.as_ref().iter().fold(0.0, |a, &b| a.max(b))
    }
}

/// The figures of per-point errors, before they are shaped into a
/// [`Figures`]: per channel and per colour, with the index of the worst
/// point (`None` without points).
#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    /// Points summarized.
    pub points: usize,
    /// Largest absolute error per channel.
    pub max_abs: Vec<f64>,
    /// 99th percentile per channel ([`p99_index`]).
    pub p99_abs: Vec<f64>,
    /// Mean per channel.
    pub mean_abs: Vec<f64>,
    /// Largest CIEDE2000 per colour.
    pub max_de: Vec<f64>,
    /// Mean CIEDE2000 per colour.
    pub mean_de: Vec<f64>,
    /// The point whose largest error over channels is the largest (the
    /// last such point).
    pub worst: Option<usize>,
}

/// Summarizes per-point errors: `abs`, `channels` absolute errors per
/// point, and `de`, `colours` CIEDE2000 per point, point after point. The
/// caller decides what a NaN counts as; sorting puts a NaN error above
/// every number, and the worst point is chosen by each point's largest
/// error, NaN left out.
pub fn summarize(abs: &[f64], channels: usize, de: &[f64], colours: usize) -> Summary {
    let n = abs.len().checked_div(channels).unwrap_or(0);
    let mut out = Summary {
        points: n,
        max_abs: vec![0.0; channels],
        p99_abs: vec![0.0; channels],
        mean_abs: vec![0.0; channels],
        max_de: vec![0.0; colours],
        mean_de: vec![0.0; colours],
        worst: None,
    };
    if n == 0 {
        return out;
    }
    for k in 0..channels {
        let mut e: Vec<f64> = (0..n).map(|p| abs[p * channels + k]).collect();
        e.sort_by(f64::total_cmp);
        out.max_abs[k] = e[n - 1];
        out.p99_abs[k] = e[p99_index(n)];
        out.mean_abs[k] = e.iter().sum::<f64>() / n as f64;
    }
    for k in 0..colours {
        let de_of = |p: usize| de[p * colours + k];
        out.max_de[k] = (0..n).map(de_of).fold(0.0, f64::max);
        out.mean_de[k] = (0..n).map(de_of).sum::<f64>() / n as f64;
    }
    out.worst = abs
        .chunks_exact(channels)
        .map(|x| x.iter().fold(0.0f64, |a, &b| a.max(b)))
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(k, _)| k);
    out
}

/// Counts of non-negative errors in bins of their f64 bit pattern (the
/// exponent and the top [`QUANTILE_BITS`] bits of the mantissa), so a
/// quantile is found in bounded memory whatever the number of points: a
/// block of counts per binary exponent that occurs (a few dozen in
/// practice, 2 kB each). Adding an error is two indexings, which matters
/// because the errors are added one by one after each parallel chunk.
pub(crate) struct P99Histogram {
    /// Indexed by the biased exponent; a block holds its mantissa bins.
    by_exponent: Vec<Option<Box<[u64; 1 << QUANTILE_BITS]>>>,
    /// NaN errors, above every number.
    nan: u64,
}

impl Default for P99Histogram {
    fn default() -> Self {
        P99Histogram {
            by_exponent: vec![None; 1 << 11],
            nan: 0,
        }
    }
}

/// Mantissa bits kept per bin: a bin spans at most 2⁻⁸ of its values, so
/// a quantile read from the histogram is within 0.4 % of the exact one.
const QUANTILE_BITS: u32 = 8;

impl P99Histogram {
    /// Counts one error.
    pub(crate) fn add(&mut self, e: f64) {
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
    pub(crate) fn p99(&self, points: usize, max: f64) -> f64 {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The histogram's p99 against sorting, over errors spread across many
    /// decades, with ties, zeros and a NaN.
    #[test]
    fn histogram_p99_is_within_its_bin_of_the_exact_one() {
        let mut state = 11u64;
        for points in [1usize, 2, 99, 100, 101, 1000, 12_345] {
            let mut h = P99Histogram::default();
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
            let rank = p99_index(points);
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
        let mut h = P99Histogram::default();
        h.add(f64::NAN);
        assert!(h.p99(1, f64::NAN).is_nan());
    }

    /// The percentile's rank against its definition, ⌈0.99·n⌉ counted
    /// from 1, on counts where the product is and is not whole.
    #[test]
    fn p99_is_rank_ceil_99_percent() {
        for (n, rank) in [
            (0, 1),
            (1, 1),
            (2, 2),
            (99, 99),
            (100, 99),
            (101, 100),
            (1000, 990),
        ] {
            assert_eq!(p99_index(n) + 1, rank, "{n} points");
        }
    }

    /// A summary of known errors: each figure by hand, the last of two
    /// equal worst points, and a NaN sorted above every number.
    #[test]
    fn a_summary_of_known_errors() {
        // Three points, two channels, one colour.
        let abs = [0.1, 0.4, 0.3, 0.2, 0.4, 0.0];
        let de = [1.0, 3.0, 2.0];
        let s = summarize(&abs, 2, &de, 1);
        assert_eq!(s.points, 3);
        assert_eq!(s.max_abs, [0.4, 0.4]);
        assert_eq!(s.p99_abs, [0.4, 0.4]);
        assert!((s.mean_abs[0] - 0.8 / 3.0).abs() < 1e-15);
        assert!((s.mean_abs[1] - 0.6 / 3.0).abs() < 1e-15);
        assert_eq!(s.max_de, [3.0]);
        assert_eq!(s.mean_de, [2.0]);
        assert_eq!(s.worst, Some(2));
        let s = summarize(&[0.1, f64::NAN, 0.2], 1, &[], 0);
        assert!(s.max_abs[0].is_nan());
        assert_eq!(s.worst, Some(2));
        let none = summarize(&[], 6, &[], 2);
        assert_eq!((none.points, none.worst, none.max_abs.len()), (0, None, 6));
    }
}
