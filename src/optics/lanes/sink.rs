//! Where the kernels' results go, one vector of wavelengths at a time:
//! stored per wavelength as [`Response`]s, or folded straight into three
//! weighted sums of R and of T (a colour), never stored. The second is what
//! every caller that turns a spectrum into a colour wants, and it spares them
//! the four-by-four transpose into `Response`s and a second pass over the
//! spectrum.

use super::arith::{Lanes, MAX_LANES};
use crate::optics::solver::Response;

/// R and T in lanes, s and p apart.
#[derive(Clone, Copy)]
pub(super) struct Power<V> {
    pub(super) rs: V,
    pub(super) rp: V,
    pub(super) ts: V,
    pub(super) tp: V,
}

impl<V: Lanes> Power<V> {
    #[inline(always)]
    /// The first [`Lanes::WIDTH`] entries hold the lanes.
    pub(super) fn responses(&self) -> [Response; MAX_LANES] {
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
    pub(super) fn from_responses(r: &[Response; MAX_LANES]) -> Self {
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

/// Takes the results of each vector of wavelengths, `start` the first
/// one's index.
pub(super) trait Sink<V: Lanes> {
    fn take(&mut self, start: usize, power: &Power<V>);
}

/// Stores every wavelength's [`Response`]; a last partial vector writes only
/// the wavelengths `out` has room for.
pub(super) struct Store<'a>(pub(super) &'a mut [Response]);

impl<V: Lanes> Sink<V> for Store<'_> {
    #[inline(always)]
    fn take(&mut self, start: usize, power: &Power<V>) {
        let res = power.responses();
        match self.0.get_mut(start..start + V::WIDTH) {
            // A fixed-length copy compiles to a few moves instead of a call.
            Some(dst) => dst.copy_from_slice(&res[..V::WIDTH]),
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
/// RGB), laid out for the kernel: each row padded with zeros to a whole
/// number of the widest vector.
#[derive(Clone, Debug, PartialEq)]
pub struct SpectralWeights {
    wavelengths: usize,
    rows: [Vec<f64>; 3],
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
        let padded = wavelengths.div_ceil(MAX_LANES) * MAX_LANES;
        SpectralWeights {
            wavelengths,
            rows: rows.map(|r| {
                let mut row = r.to_vec();
                row.resize(padded, 0.0);
                row
            }),
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

/// Wavelengths the colour integrator's dot product sums apart: sum k takes
/// the wavelengths i ≡ k (mod 8), so that the widest vector adds a whole
/// register to its sums at once, with no shuffling (see
/// `color::sampling::dot`, whose order this is).
pub(super) const PARTIAL_SUMS: usize = 8;

/// Folds each vector into running sums: per channel the eight partial sums of
/// [`PARTIAL_SUMS`], each added in wavelength order, and a serial tail for
/// the last wavelengths short of a whole eight, combined as
/// `((a0 + a4) + (a1 + a5)) + ((a2 + a6) + (a3 + a7)) + tail`. That is the
/// summation order of the colour integrator's dot product, so the sums have
/// the bits of integrating the stored spectrum, whatever the vector's width.
/// An eight-lane vector holds one set of sums per channel in a register
/// (`low`); a four-lane one needs two (`low` for residues 0–3, `high` for
/// 4–7), which alternate from vector to vector.
pub(super) struct Integrate<'a, V> {
    weights: &'a SpectralWeights,
    /// R's three channels, then T's.
    low: [V; 6],
    high: [V; 6],
    tail: [f64; 6],
}

impl<'a, V: Lanes> Integrate<'a, V> {
    #[inline(always)]
    pub(super) fn new(weights: &'a SpectralWeights) -> Self {
        Integrate {
            weights,
            low: [V::splat(0.0); 6],
            high: [V::splat(0.0); 6],
            tail: [-0.0; 6],
        }
    }

    #[inline(always)]
    pub(super) fn finish(&self) -> WeightedPower {
        let sum = |k: usize| {
            let mut a = [0.0; PARTIAL_SUMS];
            let low = self.low[k].to_array();
            a[..V::WIDTH].copy_from_slice(&low[..V::WIDTH]);
            if V::WIDTH < PARTIAL_SUMS {
                a[V::WIDTH..].copy_from_slice(&self.high[k].to_array()[..PARTIAL_SUMS - V::WIDTH]);
            }
            ((a[0] + a[4]) + (a[1] + a[5])) + ((a[2] + a[6]) + (a[3] + a[7])) + self.tail[k]
        };
        WeightedPower {
            reflectance: [sum(0), sum(1), sum(2)],
            transmittance: [sum(3), sum(4), sum(5)],
        }
    }
}

impl<V: Lanes> Sink<V> for Integrate<'_, V> {
    #[inline(always)]
    fn take(&mut self, start: usize, power: &Power<V>) {
        // No closures here: a closure is compiled without the kernel copy's
        // target features, and the intrinsics in it would not be inlined.
        let (r, t) = power.unpolarized();
        let n = self.weights.wavelengths;
        let mut products = [r; 6];
        for (c, row) in self.weights.rows.iter().enumerate() {
            let w = V::load(&row[start..]);
            products[c] = w.mul(r);
            products[3 + c] = w.mul(t);
        }
        if start + V::WIDTH <= n / PARTIAL_SUMS * PARTIAL_SUMS {
            // Vectors start at multiples of their width, so a four-lane one
            // covers residues 0–3 or 4–7 whole.
            let sums = if start.is_multiple_of(PARTIAL_SUMS) {
                &mut self.low
            } else {
                &mut self.high
            };
            for (p, s) in products.iter().zip(sums) {
                *s = s.add(*p);
            }
            return;
        }
        for (k, p) in products.iter().enumerate() {
            let p = p.to_array();
            for (l, &x) in p.iter().enumerate().take(n - start) {
                let i = start + l;
                if i < n / PARTIAL_SUMS * PARTIAL_SUMS {
                    let sums = if i % PARTIAL_SUMS < V::WIDTH {
                        &mut self.low[k]
                    } else {
                        &mut self.high[k]
                    };
                    let mut a = sums.to_array();
                    a[i % V::WIDTH] += x;
                    *sums = V::from_array(a);
                } else {
                    self.tail[k] += x;
                }
            }
        }
    }
}
