//! Values as the file stores them: rounded to f32 or through f32 to f16,
//! and refused when they do not fit.

use crate::error::{Error, Result};
use crate::lut::sample::channel_names;
use crate::lut::Kind;

/// A table must hold the values it was baked from: a gain film near a
/// lasing pole reflects far more than f16's largest value (65504), which
/// would be stored as infinity. Names the first node that does not fit
/// (`nodes`: thickness, cos θ and wavelength axes; the last unused for rgb).
pub(super) fn representable(
    data: &[f32],
    nodes: &[&[f64]; 3],
    kind: Kind,
    half: bool,
) -> Result<()> {
    let Some(k) = data.iter().position(|v| !v.is_finite()) else {
        return Ok(());
    };
    let names = channel_names(kind);
    let (node, channel) = (k / names.len(), names[k % names.len()]);
    let [t_nodes, c_nodes, w_nodes] = nodes;
    let (nt, nc) = (t_nodes.len(), c_nodes.len());
    let mut at = format!(
        "thickness {:.2} nm, cos θ {:.5}",
        t_nodes[node % nt],
        c_nodes[(node / nt) % nc]
    );
    if kind == Kind::Spectral {
        at += &format!(", wavelength {:.1} nm", w_nodes[node / (nt * nc)]);
    }
    Err(if half {
        Error::HalfOverflow {
            why: format!(
                "{channel} exceeds f16's largest value (65504) at {at}; bake in f32 (without --half) or narrow --thickness or --angles"
            ),
        }
    } else {
        Error::invalid("baked table", format!("{channel} is not finite at {at}"))
    })
}

// Used by the bench (and its tests); a library built without it has no use.
#[cfg(any(feature = "bench", test))]
impl crate::lut::Lut {
    /// This table with every value rounded to f16, for a caller that has the
    /// f32 table and wants the f16 one too without baking again: the values a
    /// `--half` bake of the same spec stores (it rounds through f32 too), but
    /// the header keeps no error figures (they measured the f32 table's
    /// rounding) and no cache key (a bake's header differs). Refused, as by
    /// the baker, when a value overflows f16.
    pub(crate) fn rounded_to_half(&self) -> Result<crate::lut::Lut> {
        let data: Vec<f32> = self
            .data()
            .iter()
            .map(|&v| stored(f64::from(v), true))
            .collect();
        let h = self.header();
        let axis = |k: usize| h.axes.get(k).map_or(&[][..], |a| &a.nodes[..]);
        representable(&data, &[axis(0), axis(1), axis(2)], h.kind, true)?;
        let mut header = h.clone();
        header.precision = "f16".into();
        header.error.bake_check = None;
        header.error.validation = None;
        header.cache_key.clear();
        Self::from_parts(header, data).map_err(|why| Error::invalid("rounded table", why))
    }
}

/// Rounds a value as it will be stored. An f16 value is rounded from the
/// f32 one, as the `half` crate's f64 conversion does on x86 with F16C; its
/// other paths (no F16C, aarch64) work from the f64, which differs where the
/// f32 value lies exactly halfway between two f16 values. Through f32
/// everywhere, a table is the same on every machine and an f32 table rounded
/// to f16 is the f16 table (see `Lut::rounded_to_half`).
#[inline]
pub(super) fn stored(v: f64, half: bool) -> f32 {
    let single = v as f32;
    if half {
        half::f16::from_f32(single).to_f32()
    } else {
        single
    }
}
