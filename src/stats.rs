//! Error figures: how far what a reader computes (an atlas read as a GPU
//! reads it, a rough table's slices, an export through its textures) is
//! from the exact values, over a set of points. One type, [`Figures`],
//! whose array shapes follow what is measured ([`ColourFigures`] for the
//! six colour channels of a smooth film, [`RoughFigures`] for F_eff's
//! three, [`AtlasFigures`] for any channel count), and one summary of
//! per-point errors, [`summarize`], with the one percentile rule,
//! [`p99_index`]. A table's validation record (`lut::ErrorStats`, with
//! its channel names, regions and a streaming histogram for its 10⁸
//! points) takes its percentile rank from here too.

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

#[cfg(test)]
mod tests {
    use super::*;

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
