//! The in-memory table and its allocation-free sampler.

use glam::Vec4;

use super::axis::Locator;
use super::header::{
    readable_version, Header, ATLAS_AXIS, COS_AXIS, NEWEST_READABLE_VERSION,
    OLDEST_READABLE_VERSION, THICKNESS_AXIS, WAVELENGTH_AXIS,
};
use super::Kind;
use crate::optics::{MAX_THICKNESS_NM, WAVELENGTH_RANGE_NM};
use crate::sweep::Side;

/// A film's unpolarized reflectance and transmittance as linear sRGB.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FilmRgb {
    /// Reflected colour (R, G, B), a perfect reflector being (1, 1, 1);
    /// components can leave [0, 1] for out-of-gamut spectra or gain layers.
    pub reflectance: [f32; 3],
    /// Colour of the power transmitted into the substrate, on the same
    /// scale as `reflectance`.
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

/// An atlas table's lookup: the charts' uniform values (see
/// [`crate::atlas::locate_f32`]) and the texels, read as a GPU reads an
/// export.
#[derive(Clone, Debug)]
struct AtlasNodes {
    uniform: Vec<f32>,
    image: crate::atlas::Image,
    /// Rows of one wavelength block of a spectral table.
    block_rows: usize,
    /// T = this − R, for a lossless film whose T is not stored.
    white: Option<[f32; 3]>,
}

impl AtlasNodes {
    fn new(header: &Header, data: &[f32]) -> Option<AtlasNodes> {
        let table = header.atlas.as_ref()?;
        let channels = header.channel_names().len();
        let blocks = header.axes.get(2).map_or(1, |w| w.nodes.len());
        Some(AtlasNodes {
            uniform: table.atlas.uniform_f32(),
            image: crate::atlas::Image {
                width: table.atlas.width,
                height: table.atlas.height * blocks,
                channels,
                data: data.to_vec(),
            },
            block_rows: table.atlas.height,
            white: table.lossless_white.map(|w| w.map(|x| x as f32)),
        })
    }

    fn rgb(&self, thickness_nm: f32, cos_theta: f32) -> FilmRgb {
        let mut v = [f32::NAN; 6];
        if let Some(t) =
            crate::atlas::locate_f32(&self.uniform, thickness_nm, cos_theta, Side::Front)
        {
            self.image.bilinear(t, &mut v);
        }
        if let Some(w) = self.white {
            for k in 0..3 {
                v[3 + k] = w[k] - v[k];
            }
        }
        FilmRgb {
            reflectance: [v[0], v[1], v[2]],
            transmittance: [v[3], v[4], v[5]],
        }
    }

    /// (R, T) of wavelength block `block` at (thickness, cos θ).
    fn spectral(&self, thickness_nm: f32, cos_theta: f32, block: usize) -> [f32; 2] {
        let mut v = [f32::NAN; 2];
        if let Some(t) =
            crate::atlas::locate_f32(&self.uniform, thickness_nm, cos_theta, Side::Front)
        {
            let offset = (block * self.block_rows) as f32;
            self.image.bilinear([t[0], t[1] + offset], &mut v);
        }
        v
    }
}

/// An rgb table's nodes as SIMD lanes: each colour as (R, G, B, 0), so a
/// lookup is a few vector lerps instead of eighteen scalar ones.
#[derive(Clone, Debug)]
enum RgbNodes {
    /// A spectral table.
    None,
    /// An atlas table (rgb or spectral).
    Atlas(AtlasNodes),
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

/// The smallest gap between neighbouring axis nodes as stored in f32: the
/// sampler divides by the gap and scales by the reciprocal of the axis span
/// times up to 65536 buckets, which must stay finite.
pub const MIN_NODE_SPACING_F32: f32 = 1e-30;

/// Checks everything in a header that the sampler and the validator index
/// by or rely on, before any pixel is read: the version; names, order and
/// count of axes and channels; axis nodes finite, strictly increasing as
/// stored (f64) and as sampled (f32) with gaps of at least
/// [`MIN_NODE_SPACING_F32`], within the ranges the format allows; the
/// stack valid and `layer` one of its layers (0 for a stack without
/// layers); the precision; error statistics with one entry per channel.
/// Returns the image size the axes give: (thickness nodes, cos θ nodes ×
/// wavelength nodes).
pub(crate) fn check_header(header: &Header) -> Result<(usize, usize), String> {
    if !readable_version(header.version.into()) {
        return Err(format!(
            "format version {} (this irid reads versions {OLDEST_READABLE_VERSION} to {NEWEST_READABLE_VERSION})",
            header.version
        ));
    }
    if (header.version == super::header::ATLAS_VERSION) != header.atlas.is_some() {
        return Err(format!(
            "format version {} {} an atlas",
            header.version,
            if header.atlas.is_some() {
                "has no"
            } else {
                "needs"
            }
        ));
    }
    check_axes(header)?;
    if let Some(table) = &header.atlas {
        check_atlas(header, table)?;
    }
    let want_channels = header.channel_names();
    let channels: Vec<String> = header
        .channels
        .iter()
        .map(|c| crate::error::escape(&c.name).into_owned())
        .collect();
    if channels != want_channels {
        return Err(format!(
            "header channels {channels:?}, a {} table has {want_channels:?}",
            header.kind
        ));
    }
    if header.precision != "f32" && header.precision != "f16" {
        return Err(format!(
            "header precision '{}', expected f32 or f16",
            crate::error::escape(&header.precision)
        ));
    }
    header
        .stack
        .validate()
        .map_err(|e| format!("header stack: {e}"))?;
    check_layer(header)?;
    // Error figures cover every quantity, stored or derived (a lossless
    // table's T).
    check_error_entries(header, channel_names(header.kind).len())?;
    image_size(header)
}

/// The axes' names and order for the table's kind, then each axis's nodes.
fn check_axes(header: &Header) -> Result<(), String> {
    let want_axes: &[&str] = match header.kind {
        Kind::Rgb => &[THICKNESS_AXIS, COS_AXIS],
        Kind::Spectral => &[THICKNESS_AXIS, COS_AXIS, WAVELENGTH_AXIS],
    };
    let names: Vec<String> = header
        .axes
        .iter()
        .map(|a| crate::error::escape(&a.name).into_owned())
        .collect();
    if names != want_axes {
        return Err(format!(
            "header axes {names:?}, a {} table has {want_axes:?}",
            header.kind
        ));
    }
    let (x_want, y_want) = if header.atlas.is_some() {
        (ATLAS_AXIS, ATLAS_AXIS)
    } else {
        (THICKNESS_AXIS, COS_AXIS)
    };
    if header.x_axis != x_want || header.y_axis != y_want {
        return Err(format!(
            "header x_axis/y_axis are {}/{}, expected {x_want}/{y_want}",
            crate::error::escape(&header.x_axis),
            crate::error::escape(&header.y_axis)
        ));
    }
    let ranges = [(0.0, MAX_THICKNESS_NM), (0.0, 1.0), WAVELENGTH_RANGE_NM];
    for (axis, (lo, hi)) in header.axes.iter().zip(ranges) {
        check_axis(axis, lo, hi)?;
    }
    Ok(())
}

/// An atlas table's charts fit its image and its domain is the axes' ends
/// (a spectral table's charts reach beyond them: they are read at d·λₖ/λ).
fn check_atlas(header: &Header, table: &super::header::TableAtlas) -> Result<(), String> {
    let atlas = &table.atlas;
    atlas.check()?;
    let ends = |k: usize| {
        let n = &header.axes[k].nodes;
        (n[0], n[n.len() - 1])
    };
    let (t0, t1) = ends(0);
    let fits = match header.kind {
        Kind::Rgb => (t0, t1) == atlas.thickness_nm,
        Kind::Spectral => atlas.thickness_nm.0 <= t0 && t1 <= atlas.thickness_nm.1,
    };
    if !fits {
        return Err(format!(
            "header atlas thickness range {:?} does not {} the thickness axis's {:?}",
            atlas.thickness_nm,
            if header.kind == Kind::Rgb {
                "equal"
            } else {
                "hold"
            },
            ends(0)
        ));
    }
    if header.axes[0].nodes.len() > 2 || header.axes[1].nodes.len() > 2 {
        return Err("an atlas table's thickness and cos θ axes list the domain's ends only".into());
    }
    if !(0.0..=1.0).contains(&table.aliased_below_cos) {
        return Err(format!(
            "header atlas aliased_below_cos {:e} is not a cos θ",
            table.aliased_below_cos
        ));
    }
    if let Some([a, b]) = table.critical_band_cos {
        if !(0.0 <= a && a <= b && b <= 1.0) {
            return Err(format!(
                "header atlas critical_band_cos [{a:e}, {b:e}] is not a band of cos θ"
            ));
        }
    }
    match table.lossless_white {
        Some(_) if header.kind != Kind::Rgb => {
            Err("only an rgb table stores reflectance alone (lossless_white)".into())
        }
        Some(w) if w.iter().any(|x| !x.is_finite()) => {
            Err("header atlas lossless_white must be finite".into())
        }
        _ => Ok(()),
    }
}

/// `layer` is one of the stack's layers, and coherent (the baker refuses a
/// thickness axis on an incoherent one), or 0 for a stack without layers.
fn check_layer(header: &Header) -> Result<(), String> {
    let layers = header.stack.layers.len();
    let layer_ok = if layers == 0 {
        header.layer == 0
    } else {
        (1..=layers).contains(&header.layer)
    };
    if !layer_ok {
        return Err(format!(
            "header layer {} is not a layer of the stack ({})",
            header.layer,
            if layers == 0 {
                "no layers: layer must be 0".to_string()
            } else {
                format!("1 to {layers}")
            }
        ));
    }
    if layers > 0 && !header.stack.layers[header.layer - 1].coherent {
        return Err(format!(
            "header layer {} is incoherent: a table's thickness axis is on a coherent layer",
            header.layer
        ));
    }
    Ok(())
}

/// The error statistics' per-channel lists have one entry per channel.
fn check_error_entries(header: &Header, n: usize) -> Result<(), String> {
    let per_channel = |what: &str, len: usize| {
        if len == n {
            Ok(())
        } else {
            Err(format!(
                "header {what} has {len} entries, one per channel ({n}) expected"
            ))
        }
    };
    if let Some(check) = &header.error.bake_check {
        per_channel("error.bake_check.max_abs", check.max_abs.len())?;
    }
    if let Some(v) = &header.error.validation {
        per_channel("error.validation.channels", v.channels.len())?;
        per_channel("error.validation.max_abs", v.figures.max_abs.len())?;
        per_channel("error.validation.mean_abs", v.figures.mean_abs.len())?;
        per_channel("error.validation.p99_abs", v.figures.p99_abs.len())?;
    }
    Ok(())
}

/// (thickness nodes, cos θ nodes × wavelength nodes), refused beyond what
/// an OpenEXR image's i32 dimensions hold.
fn image_size(header: &Header) -> Result<(usize, usize), String> {
    let (width, rows) = match &header.atlas {
        Some(t) => (t.atlas.width, t.atlas.height),
        None => (header.axes[0].nodes.len(), header.axes[1].nodes.len()),
    };
    let height = rows
        .checked_mul(header.axes.get(2).map_or(1, |w| w.nodes.len()))
        .filter(|_| width <= i32::MAX as usize)
        .filter(|&h| h <= i32::MAX as usize)
        .ok_or("header axes have more nodes than an OpenEXR image holds")?;
    Ok((width, height))
}

/// One axis: nodes present, finite, within [lo, hi], strictly increasing
/// as f64 and as the f32 the sampler uses, with gaps it can divide by.
fn check_axis(axis: &super::Axis, lo: f64, hi: f64) -> Result<(), String> {
    let name = &axis.name;
    let nodes = &axis.nodes;
    if nodes.is_empty() {
        return Err(format!("axis {name} has no nodes"));
    }
    if let Some(&x) = nodes.iter().find(|&&x| !(lo..=hi).contains(&x)) {
        return Err(format!(
            "axis {name} node {x:e} is outside the format's range {lo:e} to {hi:e}"
        ));
    }
    if let Some(k) = nodes.windows(2).position(|w| w[1] <= w[0]) {
        return Err(format!(
            "axis {name} nodes must be strictly increasing: node {} ({:e}) follows {:e}",
            k + 2,
            nodes[k + 1],
            nodes[k]
        ));
    }
    if let Some(k) = nodes.windows(2).position(|w| {
        (w[1] as f32 - w[0] as f32)
            .partial_cmp(&MIN_NODE_SPACING_F32)
            .is_none_or(|o| o.is_lt())
    }) {
        return Err(format!(
            "axis {name} nodes {} and {} ({:e} and {:e}) are closer than the f32 sampler resolves (equal as f32, or less than {MIN_NODE_SPACING_F32:e} apart)",
            k + 1,
            k + 2,
            nodes[k],
            nodes[k + 1]
        ));
    }
    Ok(())
}

pub(crate) fn channel_names(kind: Kind) -> &'static [&'static str] {
    match kind {
        Kind::Rgb => &RGB_CHANNELS,
        Kind::Spectral => &SPECTRAL_CHANNELS,
    }
}

impl Lut {
    /// Checks that the header describes `data` (see [`check_header`]) and
    /// that every value is finite, and builds the lookup. The error says
    /// what disagrees.
    pub(crate) fn from_parts(header: Header, data: Vec<f32>) -> Result<Lut, String> {
        let (width, height) = check_header(&header)?;
        let want_channels = header.channel_names();
        let values = width
            .checked_mul(height)
            .and_then(|n| n.checked_mul(want_channels.len()));
        if values != Some(data.len()) {
            return Err(format!(
                "header axes give {width}x{height} nodes × {} channels but the image holds {} values",
                want_channels.len(),
                data.len()
            ));
        }
        if let Some(at) = data.iter().position(|v| !v.is_finite()) {
            let node = at / want_channels.len();
            if header.atlas.is_some() {
                return Err(format!(
                    "channel {} is {} at texel ({}, {}): table values must be finite",
                    want_channels[at % want_channels.len()],
                    data[at],
                    node % width,
                    node / width
                ));
            }
            let (i, row) = (node % width, node / width);
            let n_cos = header.axes[1].nodes.len();
            return Err(format!(
                "channel {} is {} at thickness {} nm, cos θ {}{}: table values must be finite",
                want_channels[at % want_channels.len()],
                data[at],
                header.axes[0].nodes[i],
                header.axes[1].nodes[row % n_cos],
                header
                    .axes
                    .get(2)
                    .map_or(String::new(), |w| format!(", {} nm", w.nodes[row / n_cos])),
            ));
        }
        let rgb_nodes = match AtlasNodes::new(&header, &data) {
            Some(atlas) => RgbNodes::Atlas(atlas),
            None => RgbNodes::new(header.kind, &data),
        };
        Ok(Lut {
            rgb_nodes,
            thickness: Locator::new(&header.axes[0].nodes),
            cos: Locator::new(&header.axes[1].nodes),
            wavelength: header.axes.get(2).map(|a| Locator::new(&a.nodes)),
            header,
            data,
        })
    }

    /// The table's header: axes, channels, stack, colorimetry and error
    /// figures, as read from or written to the file's `irid` attribute.
    pub fn header(&self) -> &Header {
        &self.header
    }

    pub(crate) fn header_mut(&mut self) -> &mut Header {
        &mut self.header
    }

    /// Whether the table holds rgb colours or a spectral response (the
    /// header's `kind`), which decides the layout of [`Lut::data`].
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
        if let RgbNodes::Atlas(atlas) = &self.rgb_nodes {
            if self.header.kind != Kind::Rgb {
                return FilmRgb {
                    reflectance: [f32::NAN; 3],
                    transmittance: [f32::NAN; 3],
                };
            }
            return atlas.rgb(thickness_nm, cos_theta);
        }
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
            RgbNodes::None | RgbNodes::Atlas(_) => (Vec4::NAN, Vec4::NAN),
        };
        FilmRgb {
            reflectance: [r.x, r.y, r.z],
            transmittance: [t.x, t.y, t.z],
        }
    }

    /// Whether [`Lut::sample_rgb`] reads reflectance only and takes the
    /// transmittance as its complement (an rgb table of a lossless film).
    pub fn samples_as_lossless(&self) -> bool {
        match &self.rgb_nodes {
            RgbNodes::Lossless { .. } => true,
            RgbNodes::Atlas(a) => a.white.is_some(),
            _ => false,
        }
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
        if let RgbNodes::Atlas(atlas) = &self.rgb_nodes {
            // Each node's block at the same d/λ (see docs/lut-format.md):
            // the thickness clamped to the table's range, the wavelength to
            // the nodes (NaN to the first node, at its own thickness).
            let (k, fz) = wl.locate(wavelength_nm);
            let d = self.thickness.clamp(thickness_nm);
            let nodes = &self.header.axes[2].nodes;
            let upper = (k + 1).min(wl.len() - 1);
            let (lo, hi) = (nodes[k] as f32, nodes[upper] as f32);
            let lambda = if wavelength_nm.is_nan() {
                lo
            } else {
                wavelength_nm.clamp(lo, nodes[wl.len() - 1] as f32)
            };
            let a = atlas.spectral(d * (lo / lambda), cos_theta, k);
            let b = atlas.spectral(d * (hi / lambda), cos_theta, upper);
            return (a[0] + fz * (b[0] - a[0]), a[1] + fz * (b[1] - a[1]));
        }
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
