//! Where the kernels' results go, one group of four wavelengths at a time:
//! stored per wavelength as [`Response`]s, or folded straight into three
//! weighted sums of R and of T (a colour), never stored. The second is what
//! every caller that turns a spectrum into a colour wants, and it spares them
//! the four-by-four transpose into `Response`s and a second pass over the
//! spectrum.

use super::arith::{Lanes, LANES};
use crate::optics::solver::Response;

/// R and T of four lanes, s and p apart.
#[derive(Clone, Copy)]
pub(super) struct Power<V> {
    pub(super) rs: V,
    pub(super) rp: V,
    pub(super) ts: V,
    pub(super) tp: V,
}

impl<V: Lanes> Power<V> {
    #[inline(always)]
    pub(super) fn responses(&self) -> [Response; LANES] {
        let (rs, rp) = (self.rs.to_array(), self.rp.to_array());
        let (ts, tp) = (self.ts.to_array(), self.tp.to_array());
        std::array::from_fn(|l| Response {
            rs: rs[l],
            rp: rp[l],
            ts: ts[l],
            tp: tp[l],
        })
    }

    #[inline(always)]
    pub(super) fn from_responses(r: &[Response; LANES]) -> Self {
        Power {
            rs: V::from_array(r.map(|x| x.rs)),
            rp: V::from_array(r.map(|x| x.rp)),
            ts: V::from_array(r.map(|x| x.ts)),
            tp: V::from_array(r.map(|x| x.tp)),
        }
    }

    /// Unpolarized (R, T), as [`Response::r`] and [`Response::t`] compute them.
    #[inline(always)]
    fn unpolarized(&self) -> (V, V) {
        let half = V::splat(0.5);
        (
            half.mul(self.rs.add(self.rp)),
            half.mul(self.ts.add(self.tp)),
        )
    }
}

/// Takes each group's results; `group` counts groups of [`LANES`]
/// wavelengths from the first.
pub(super) trait Sink<V: Lanes> {
    fn take(&mut self, group: usize, power: &Power<V>);
}

/// Stores every wavelength's [`Response`]; a last partial group writes only
/// the wavelengths `out` has room for.
pub(super) struct Store<'a>(pub(super) &'a mut [Response]);

impl<V: Lanes> Sink<V> for Store<'_> {
    #[inline(always)]
    fn take(&mut self, group: usize, power: &Power<V>) {
        let res = power.responses();
        let start = group * LANES;
        match self.0.get_mut(start..start + LANES) {
            // A fixed-length copy compiles to a few moves instead of a call.
            Some(dst) => dst.copy_from_slice(&res),
            None => {
                let rest = &mut self.0[start..];
                let n = rest.len();
                rest.copy_from_slice(&res[..n]);
            }
        }
    }
}

/// Three rows of weights over a spectrum's wavelengths (say the colour
/// matching functions times an illuminant, or the rows that give linear
/// RGB), laid out per group of four wavelengths for the kernel.
#[derive(Clone, Debug, PartialEq)]
pub struct SpectralWeights {
    wavelengths: usize,
    /// [group][channel][lane]; the unused lanes of a last partial group hold 0.
    groups: Vec<[[f64; LANES]; 3]>,
}

impl SpectralWeights {
    /// The weights `rows[c][i]` of channel c at wavelength i.
    ///
    /// # Panics
    /// If the rows differ in length.
    pub fn new(rows: [&[f64]; 3]) -> SpectralWeights {
        let wavelengths = rows[0].len();
        assert!(
            rows.iter().all(|r| r.len() == wavelengths),
            "weights: every channel needs one weight per wavelength"
        );
        let groups = (0..wavelengths.div_ceil(LANES))
            .map(|g| {
                std::array::from_fn(|c| {
                    std::array::from_fn(|l| rows[c].get(g * LANES + l).copied().unwrap_or(0.0))
                })
            })
            .collect();
        SpectralWeights {
            wavelengths,
            groups,
        }
    }

    /// How many wavelengths the weights cover.
    pub fn len(&self) -> usize {
        self.wavelengths
    }

    /// True when the weights cover no wavelength.
    pub fn is_empty(&self) -> bool {
        self.wavelengths == 0
    }
}

/// The weighted sums Σ w_c(λ) R(λ) and Σ w_c(λ) T(λ) of one spectrum, for the
/// three channels of a [`SpectralWeights`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WeightedPower {
    /// Σ w_c(λ) R(λ), R the unpolarized reflectance.
    pub reflectance: [f64; 3],
    /// Σ w_c(λ) T(λ), T the unpolarized transmittance.
    pub transmittance: [f64; 3],
}

/// Folds each group into running sums: per channel one vector of four partial
/// sums (lane l sums the wavelengths i ≡ l mod 4) and, for a last partial
/// group, a serial tail, combined as `(a0 + a1) + (a2 + a3) + tail`. That is
/// the summation order of the colour integrator's dot product, so the sums
/// have the same bits as integrating the stored spectrum.
pub(super) struct Integrate<'a, V> {
    weights: &'a SpectralWeights,
    /// R's three channels, then T's.
    partial: [V; 6],
    tail: [f64; 6],
}

impl<'a, V: Lanes> Integrate<'a, V> {
    #[inline(always)]
    pub(super) fn new(weights: &'a SpectralWeights) -> Self {
        Integrate {
            weights,
            partial: [V::splat(0.0); 6],
            tail: [-0.0; 6],
        }
    }

    #[inline(always)]
    pub(super) fn finish(&self) -> WeightedPower {
        let sum = |k: usize| {
            let a = self.partial[k].to_array();
            (a[0] + a[1]) + (a[2] + a[3]) + self.tail[k]
        };
        WeightedPower {
            reflectance: [sum(0), sum(1), sum(2)],
            transmittance: [sum(3), sum(4), sum(5)],
        }
    }
}

impl<V: Lanes> Sink<V> for Integrate<'_, V> {
    #[inline(always)]
    fn take(&mut self, group: usize, power: &Power<V>) {
        let w = &self.weights.groups[group];
        let (r, t) = power.unpolarized();
        let used = self.weights.wavelengths - group * LANES;
        let (r_sums, t_sums) = self.partial.split_at_mut(3);
        if used >= LANES {
            for ((wc, r_sum), t_sum) in w.iter().zip(r_sums).zip(t_sums) {
                let wc = V::from_array(*wc);
                *r_sum = r_sum.add(wc.mul(r));
                *t_sum = t_sum.add(wc.mul(t));
            }
            return;
        }
        let (r, t) = (r.to_array(), t.to_array());
        let (r_tail, t_tail) = self.tail.split_at_mut(3);
        for l in 0..used {
            for ((wc, r_sum), t_sum) in w.iter().zip(&mut *r_tail).zip(&mut *t_tail) {
                *r_sum += wc[l] * r[l];
                *t_sum += wc[l] * t[l];
            }
        }
    }
}
