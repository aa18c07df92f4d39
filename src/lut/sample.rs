//! The in-memory table and its allocation-free sampler.

use glam::Vec4;

use super::axis::Locator;
use super::header::{
    readable_version, Header, COS_AXIS, OLDEST_READABLE_VERSION, THICKNESS_AXIS, WAVELENGTH_AXIS,
    WHITE_E_VERSION,
};
use super::Kind;

/// A film's unpolarized reflectance and transmittance as linear sRGB.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FilmRgb {
    pub reflectance: [f32; 3],
    pub transmittance: [f32; 3],
}

/// A loaded or freshly baked table.
///
/// Values live in one contiguous f32 array, thickness fastest: for the rgb
/// kind `[cos][thickness][6]` (reflectance R, G, B, transmittance R, G, B),
/// for the spectral kind `[wavelength][cos][thickness][2]` (R, T).
#[derive(Clone, Debug)]
pub struct Lut {
    header: Header,
    thickness: Locator,
    cos: Locator,
    wavelength: Option<Locator>,
    data: Vec<f32>,
    /// The rgb kind's nodes again, laid out for [`Lut::sample_rgb`].
    rgb_nodes: RgbNodes,
}

/// An rgb table's nodes as SIMD lanes: each colour as (R, G, B, 0), so a
/// lookup is a few vector lerps instead of eighteen scalar ones.
#[derive(Clone, Debug)]
enum RgbNodes {
    /// A spectral table.
    None,
    /// Reflectance and transmittance at every node.
    Full(Vec<[Vec4; 2]>),
    /// Every node's R + T is the same colour: a lossless film, where what
    /// is not reflected is transmitted. Only R is stored and read, and
    /// T = white − R (half the reads of a lookup, at every film hit).
    Lossless { reflectance: Vec<Vec4>, white: Vec4 },
}

/// How far R + T may stray from one colour across a table for it to be
/// sampled as lossless: a few f32 roundings of values near 1, far below
/// any table's interpolation error.
const LOSSLESS_TOLERANCE: f32 = 1e-5;

impl RgbNodes {
    fn new(kind: Kind, data: &[f32]) -> RgbNodes {
        if kind != Kind::Rgb {
            return RgbNodes::None;
        }
        let color = |v: &[f32]| Vec4::new(v[0], v[1], v[2], 0.0);
        let nodes = data.chunks_exact(6);
        let white = data.get(..6).map(|v| color(v) + color(&v[3..]));
        let lossless = white.filter(|&white| {
            nodes.clone().all(|v| {
                let sum = color(v) + color(&v[3..]);
                sum.is_finite() && (sum - white).abs().max_element() <= LOSSLESS_TOLERANCE
            })
        });
        match lossless {
            Some(white) => RgbNodes::Lossless {
                reflectance: nodes.map(color).collect(),
                white,
            },
            None => RgbNodes::Full(nodes.map(|v| [color(v), color(&v[3..])]).collect()),
        }
    }
}

/// The four corners of the cell whose lower corner is `at`, the next node
/// `dx` along thickness and `dy` along cos θ (either may be 0 on a
/// one-node axis), under one bounds check.
#[inline(always)]
fn cell_corners<T: Copy>(nodes: &[T], at: usize, dx: usize, dy: usize) -> [T; 4] {
    let cell = &nodes[at..=at + dy + dx];
    // SAFETY: 0, dx and dy are at most dy + dx, the last index of `cell`
    // (bounds-checked when it was sliced).
    let corner = |k: usize| unsafe { *cell.get_unchecked(k) };
    [corner(0), corner(dx), corner(dy), corner(dy + dx)]
}

pub(crate) const RGB_CHANNELS: [&str; 6] = [
    "reflectance.R",
    "reflectance.G",
    "reflectance.B",
    "transmittance.R",
    "transmittance.G",
    "transmittance.B",
];
pub(crate) const SPECTRAL_CHANNELS: [&str; 2] = ["reflectance", "transmittance"];

pub(crate) fn channel_names(kind: Kind) -> &'static [&'static str] {
    match kind {
        Kind::Rgb => &RGB_CHANNELS,
        Kind::Spectral => &SPECTRAL_CHANNELS,
    }
}

impl Lut {
    /// Checks that the header describes `data` (names, order and count of
    /// axes and channels, increasing finite nodes, node counts against the
    /// value count) and builds the lookup. The error says what disagrees.
    pub(crate) fn from_parts(header: Header, data: Vec<f32>) -> Result<Lut, String> {
        if !readable_version(header.version.into()) {
            return Err(format!(
                "format version {} (this irid reads versions {OLDEST_READABLE_VERSION} to {WHITE_E_VERSION})",
                header.version
            ));
        }
        let want_axes: &[&str] = match header.kind {
            Kind::Rgb => &[THICKNESS_AXIS, COS_AXIS],
            Kind::Spectral => &[THICKNESS_AXIS, COS_AXIS, WAVELENGTH_AXIS],
        };
        let names: Vec<&str> = header.axes.iter().map(|a| a.name.as_str()).collect();
        if names != want_axes {
            return Err(format!(
                "header axes {names:?}, a {} table has {want_axes:?}",
                header.kind
            ));
        }
        if header.x_axis != THICKNESS_AXIS || header.y_axis != COS_AXIS {
            return Err(format!(
                "header x_axis/y_axis are {}/{}, expected {THICKNESS_AXIS}/{COS_AXIS}",
                header.x_axis, header.y_axis
            ));
        }
        for axis in &header.axes {
            if axis.nodes.is_empty() {
                return Err(format!("axis {} has no nodes", axis.name));
            }
            if axis.nodes.iter().any(|x| !x.is_finite())
                || axis.nodes.windows(2).any(|w| w[1] <= w[0])
            {
                return Err(format!(
                    "axis {} nodes must be finite and strictly increasing",
                    axis.name
                ));
            }
        }
        let cos = &header.axes[1].nodes;
        if cos[0] < 0.0 || cos[cos.len() - 1] > 1.0 {
            return Err("axis cos_theta nodes must lie in [0, 1]".into());
        }
        let want_channels = channel_names(header.kind);
        let channels: Vec<&str> = header.channels.iter().map(|c| c.name.as_str()).collect();
        if channels != want_channels {
            return Err(format!(
                "header channels {channels:?}, a {} table has {want_channels:?}",
                header.kind
            ));
        }
        let nodes: usize = header.axes.iter().map(|a| a.nodes.len()).product();
        if nodes.checked_mul(want_channels.len()) != Some(data.len()) {
            return Err(format!(
                "header axes give {} nodes × {} channels but the image holds {} values",
                nodes,
                want_channels.len(),
                data.len()
            ));
        }
        let rgb_nodes = RgbNodes::new(header.kind, &data);
        Ok(Lut {
            rgb_nodes,
            thickness: Locator::new(&header.axes[0].nodes),
            cos: Locator::new(&header.axes[1].nodes),
            wavelength: header.axes.get(2).map(|a| Locator::new(&a.nodes)),
            header,
            data,
        })
    }

    pub fn header(&self) -> &Header {
        &self.header
    }

    pub(crate) fn header_mut(&mut self) -> &mut Header {
        &mut self.header
    }

    pub fn kind(&self) -> Kind {
        self.header.kind
    }

    /// The raw values in the layout described on [`Lut`].
    pub fn data(&self) -> &[f32] {
        &self.data
    }

    /// Bilinear in thickness and cos θ. Inputs outside an axis are clamped
    /// to its end (NaN to its start): the table never extrapolates. On a
    /// spectral table every component is NaN. Allocates nothing.
    #[inline(always)]
    pub fn sample_rgb(&self, thickness_nm: f32, cos_theta: f32) -> FilmRgb {
        let (i, fx) = self.thickness.locate(thickness_nm);
        let (j, fy) = self.cos.locate(cos_theta);
        let nt = self.thickness.len();
        let dx = usize::from(nt > 1);
        let dy = if self.cos.len() > 1 { nt } else { 0 };
        let at = j * nt + i;
        // The same a + f·(b − a) per channel as `bilerp`, four lanes at once.
        let lerp = |a: Vec4, b: Vec4, f: f32| a + (b - a) * f;
        let (r, t) = match &self.rgb_nodes {
            RgbNodes::Lossless { reflectance, white } => {
                let [v00, v10, v01, v11] = cell_corners(reflectance, at, dx, dy);
                let r = lerp(lerp(v00, v10, fx), lerp(v01, v11, fx), fy);
                (r, *white - r)
            }
            RgbNodes::Full(full) => {
                let [v00, v10, v01, v11] = cell_corners(full, at, dx, dy);
                (
                    lerp(lerp(v00[0], v10[0], fx), lerp(v01[0], v11[0], fx), fy),
                    lerp(lerp(v00[1], v10[1], fx), lerp(v01[1], v11[1], fx), fy),
                )
            }
            RgbNodes::None => (Vec4::NAN, Vec4::NAN),
        };
        FilmRgb {
            reflectance: [r.x, r.y, r.z],
            transmittance: [t.x, t.y, t.z],
        }
    }

    /// Whether [`Lut::sample_rgb`] reads reflectance only and takes the
    /// transmittance as its complement (an rgb table of a lossless film).
    pub fn samples_as_lossless(&self) -> bool {
        matches!(self.rgb_nodes, RgbNodes::Lossless { .. })
    }

    /// Trilinear (R, T) at one wavelength; clamped like [`Lut::sample_rgb`].
    /// On an rgb table both are NaN. Allocates nothing.
    #[inline]
    pub fn sample_spectral(
        &self,
        thickness_nm: f32,
        cos_theta: f32,
        wavelength_nm: f32,
    ) -> (f32, f32) {
        let Some(wl) = &self.wavelength else {
            return (f32::NAN, f32::NAN);
        };
        let (i, fx) = self.thickness.locate(thickness_nm);
        let (j, fy) = self.cos.locate(cos_theta);
        let (k, fz) = wl.locate(wavelength_nm);
        let nt = self.thickness.len();
        let plane = nt * self.cos.len() * 2;
        let dx = if nt > 1 { 2 } else { 0 };
        let dy = if self.cos.len() > 1 { 2 * nt } else { 0 };
        let dz = if wl.len() > 1 { plane } else { 0 };
        let base = k * plane + (j * nt + i) * 2;
        let a: [f32; 2] = bilerp(&self.data, base, dx, dy, fx, fy);
        let b: [f32; 2] = bilerp(&self.data, base + dz, dx, dy, fx, fy);
        (a[0] + fz * (b[0] - a[0]), a[1] + fz * (b[1] - a[1]))
    }
}

#[inline]
fn bilerp<const N: usize>(
    data: &[f32],
    base: usize,
    dx: usize,
    dy: usize,
    fx: f32,
    fy: f32,
) -> [f32; N] {
    let v00 = &data[base..base + N];
    let v10 = &data[base + dx..base + dx + N];
    let v01 = &data[base + dy..base + dy + N];
    let v11 = &data[base + dy + dx..base + dy + dx + N];
    let mut out = [0.0; N];
    for k in 0..N {
        let lo = v00[k] + fx * (v10[k] - v00[k]);
        let hi = v01[k] + fx * (v11[k] - v01[k]);
        out[k] = lo + fy * (hi - lo);
    }
    out
}
