//! Which layers a fit varies, and within which bounds.

use crate::error::{short_number, Error, Result};
use crate::optics::{Stack, MAX_THICKNESS_NM};

/// The varied layers (1-based from the top, as stack files number them)
/// and each one's thickness bounds in nm.
#[derive(Clone, Debug, PartialEq)]
pub struct Vary {
    /// Layer numbers, 1 to N from the ambient side, each at most once.
    pub layers: Vec<usize>,
    /// Closed bounds (lo, hi) per varied layer, in nm.
    pub bounds_nm: Vec<(f64, f64)>,
}

impl Vary {
    /// Checks `layers` against `stack` and the bounds against each layer's
    /// thickness in the stack (the start, which must lie inside them).
    /// Without `bounds`, each layer may move ±50 % around its thickness.
    /// Errors name `layers_arg` or `bounds_arg`.
    pub fn new(
        stack: &Stack,
        layers: &[usize],
        bounds: Option<&[(f64, f64)]>,
        layers_arg: &str,
        bounds_arg: &str,
    ) -> Result<Vary> {
        if layers.is_empty() {
            return Err(Error::invalid(layers_arg, "names no layer"));
        }
        let count = stack.layers.len();
        for (i, &layer) in layers.iter().enumerate() {
            let why = if layer == 0 {
                Some("0 names no layer: layers are numbered from 1 at the ambient side".to_string())
            } else if layer == count + 1 {
                Some(format!(
                    "{layer} is the substrate, a semi-infinite medium with no thickness (the stack has {count} layers)"
                ))
            } else if layer > count {
                Some(format!("{layer} names no layer: the stack has {count}"))
            } else if layers[..i].contains(&layer) {
                Some(format!("layer {layer} is named twice"))
            } else {
                None
            };
            if let Some(why) = why {
                return Err(Error::invalid(layers_arg, why));
            }
        }
        let bounds_nm = match bounds {
            Some(b) => {
                if b.len() != layers.len() {
                    return Err(Error::invalid(
                        bounds_arg,
                        format!(
                            "{} ranges for {} varied layers (one per layer)",
                            b.len(),
                            layers.len()
                        ),
                    ));
                }
                b.to_vec()
            }
            None => layers
                .iter()
                .map(|&l| {
                    let d = stack.layers[l - 1].thickness_nm;
                    (0.5 * d, 1.5 * d)
                })
                .collect(),
        };
        for (k, (&layer, &(lo, hi))) in layers.iter().zip(&bounds_nm).enumerate() {
            let what = format!("{bounds_arg}[{k}]");
            if !(lo >= 0.0 && hi <= MAX_THICKNESS_NM && lo <= hi) {
                return Err(Error::invalid(
                    what,
                    format!(
                        "{}:{} nm must satisfy 0 ≤ lo ≤ hi ≤ {MAX_THICKNESS_NM:e}",
                        short_number(lo),
                        short_number(hi)
                    ),
                ));
            }
            let start = stack.layers[layer - 1].thickness_nm;
            if !(lo..=hi).contains(&start) {
                return Err(Error::invalid(
                    what,
                    format!(
                        "{}:{} nm excludes the start, layer {layer}'s thickness {} nm",
                        short_number(lo),
                        short_number(hi),
                        short_number(start)
                    ),
                ));
            }
            if hi == lo && bounds.is_none() {
                return Err(Error::invalid(
                    bounds_arg,
                    format!("layer {layer} has thickness 0: give its bounds"),
                ));
            }
        }
        Ok(Vary {
            layers: layers.to_vec(),
            bounds_nm,
        })
    }

    /// The varied layers' thicknesses in `stack`: the start.
    pub fn start(&self, stack: &Stack) -> Vec<f64> {
        self.layers
            .iter()
            .map(|&l| stack.layers[l - 1].thickness_nm)
            .collect()
    }

    /// `stack` with the varied layers set to `x`.
    pub fn apply(&self, stack: &Stack, x: &[f64]) -> Stack {
        let mut out = stack.clone();
        for (&l, &d) in self.layers.iter().zip(x) {
            out.layers[l - 1].thickness_nm = d;
        }
        out
    }

    /// The full thickness list of `base` (all layers) with the varied ones
    /// set to `x`, into `out`.
    pub fn fill(&self, base: &[f64], x: &[f64], out: &mut Vec<f64>) {
        out.clear();
        out.extend_from_slice(base);
        for (&l, &d) in self.layers.iter().zip(x) {
            out[l - 1] = d;
        }
    }
}
