//! Atlases of charts: a film's response over (thickness, cos θ) held as
//! rectangles of texels, each with its own closed-form coordinates, chosen
//! in closed form per lookup and read by one bilinear filter. GPU exports
//! and tables alike store their nodes this way; [`search`] chooses the
//! charts and their sizes for an error target. A texel holds a colour
//! film's six channels or a spectral film's R and T at the wavelength
//! nodes [`spectrum`] chooses (see [`Film::channels`]).
//!
//! The layout of the uniform values a shader reads is specified in
//! docs/gpu.md, the table file in docs/lut-format.md.

mod chart;
mod eval;
mod pack;
pub mod search;
pub mod spectrum;

pub use chart::{
    texel_f32, Chart, Coords, CosAxis, LogAxis, Optical, Rect, OPTICAL_FLOOR, PARAMS_PER_CHART,
};
pub use eval::{Film, LASING_BOUND};
pub use pack::pack;

use serde::{Deserialize, Serialize};

use crate::sweep::Side;

/// The most charts one atlas holds (both sides together): the shader's
/// uniform array has room for this many.
pub const MAX_CHARTS: usize = 32;

/// vec4 of the uniform array before the first chart's.
pub const HEADER_VEC4: usize = 2;

/// The uniform array's length in vec4: the header and every chart's.
pub const UNIFORM_VEC4: usize = HEADER_VEC4 + MAX_CHARTS * PARAMS_PER_CHART / 4;

/// Charts in one rectangle of texels, and the thickness range lookups are
/// clamped to.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Atlas {
    /// Texels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// The varying layer's thickness range (nm); lookups clamp to it.
    pub thickness_nm: (f64, f64),
    /// Per side, corners first, then bands by increasing cos θ (the order
    /// the choice rule reads them in).
    pub charts: Vec<Chart>,
}

impl Atlas {
    /// The uniform values a shader reads, as f32: (width, height, chart
    /// count, the side whose charts side-1 lookups read), (thickness min,
    /// max, 0, 0), then each chart's [`Chart::params`], zeros up to
    /// [`UNIFORM_VEC4`] vec4. Side-1 lookups read side 1's charts when
    /// there are any, else side 0's (a film that reads the same from both
    /// sides, or one no light crosses).
    pub fn uniform_f32(&self) -> Vec<f32> {
        let mut v = vec![0.0f32; 4 * UNIFORM_VEC4];
        let back = if self.charts.iter().any(|c| c.side == Side::Back) {
            1.0
        } else {
            0.0
        };
        v[..4].copy_from_slice(&[
            self.width as f32,
            self.height as f32,
            self.charts.len() as f32,
            back,
        ]);
        v[4] = self.thickness_nm.0 as f32;
        v[5] = self.thickness_nm.1 as f32;
        for (k, chart) in self.charts.iter().enumerate() {
            let at = 4 * HEADER_VEC4 + k * PARAMS_PER_CHART;
            v[at..at + PARAMS_PER_CHART].copy_from_slice(&chart.params());
        }
        v
    }

    /// Checks what a reader indexes by: at most [`MAX_CHARTS`] charts, each
    /// inside the image with at least one texel, finite parameters within
    /// their ranges, and a thickness range 0 ≤ min ≤ max.
    pub fn check(&self) -> Result<(), String> {
        let (t0, t1) = self.thickness_nm;
        if !(t0 >= 0.0 && t0 <= t1 && t1.is_finite()) {
            return Err(format!("atlas thickness range {t0}:{t1}"));
        }
        if self.charts.len() > MAX_CHARTS {
            return Err(format!(
                "{} charts, at most {MAX_CHARTS}",
                self.charts.len()
            ));
        }
        for (k, chart) in self.charts.iter().enumerate() {
            let r = chart.rect;
            let fits = r.width >= 1
                && r.height >= 1
                && r.x.checked_add(r.width).is_some_and(|e| e <= self.width)
                && r.y.checked_add(r.height).is_some_and(|e| e <= self.height);
            if !fits {
                return Err(format!(
                    "chart {k}'s rectangle {r:?} is outside the {}x{} atlas",
                    self.width, self.height
                ));
            }
            chart.check().map_err(|why| format!("chart {k}: {why}"))?;
        }
        Ok(())
    }

    /// The chart that serves (d, c) on `side` by the rule the shader
    /// applies (in f64): the first corner of the side whose radius holds
    /// it, else the first band of the side whose cos θ range reaches up to
    /// c, else the side's last band. `None` when the side has no chart.
    pub fn chart_for(&self, d: f64, c: f64, side: Side) -> Option<usize> {
        let d = d.clamp(self.thickness_nm.0, self.thickness_nm.1);
        let mut last = None;
        for (k, chart) in self.charts.iter().enumerate() {
            if chart.side != side {
                continue;
            }
            match chart.coords {
                Coords::Corner { .. } if chart.in_corner(d, c) => return Some(k),
                Coords::Corner { .. } => {}
                Coords::Band { c: ca, .. } => {
                    last = Some(k);
                    if c <= ca.hi {
                        return Some(k);
                    }
                }
            }
        }
        last
    }
}

/// The shader's lookup in f32 from the uniform values `u` (see
/// [`Atlas::uniform_f32`]): the texel position (x, y in texels) a film at
/// `d` nm and cos θ `c` is read at on `side` (any side but 0 reads the
/// side the header names), or `None` when that side has no chart.
/// Operation for operation `irid_atlas_texel` of the shaders (generated by
/// gpu/src/generate.rs).
pub fn locate_f32(u: &[f32], d: f32, c: f32, side: Side) -> Option<[f32; 2]> {
    let count = u[2] as usize;
    let side = match side {
        Side::Front => 0,
        Side::Back => u[3] as u32,
    };
    let d = d.max(u[4]).min(u[5]);
    let c = c.clamp(0.0, 1.0);
    let chart = |k: usize| -> &[f32; PARAMS_PER_CHART] {
        let at = 4 * HEADER_VEC4 + k * PARAMS_PER_CHART;
        u[at..at + PARAMS_PER_CHART]
            .try_into()
            .expect("chart slice")
    };
    let mut last = None;
    for k in 0..count.min(MAX_CHARTS) {
        let q = chart(k);
        if q[4] as u32 != side {
            continue;
        }
        if q[5] > 0.5 {
            let s = (1.0 - q[6] * (1.0 - c * c)).max(q[7] * q[7]).sqrt();
            let pp = d * s / q[8];
            if (pp * pp + c * c).sqrt() < q[9] {
                return Some(texel_f32(q, d, c));
            }
            continue;
        }
        last = Some(k);
        if c <= q[13] {
            return Some(texel_f32(q, d, c));
        }
    }
    last.map(|k| texel_f32(chart(k), d, c))
}

/// An image of `channels` f32 values per texel, row-major, row 0 first.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Texels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Values per texel.
    pub channels: usize,
    /// `width × height × channels` values.
    pub data: Vec<f32>,
}

impl Image {
    /// A zero image.
    pub fn new(width: usize, height: usize, channels: usize) -> Image {
        Image {
            width,
            height,
            channels,
            data: vec![0.0; width * height * channels],
        }
    }

    /// The texel at column x, row y.
    pub fn texel(&self, x: usize, y: usize) -> &[f32] {
        let at = (y * self.width + x) * self.channels;
        &self.data[at..at + self.channels]
    }

    /// Mutable texel.
    pub fn texel_mut(&mut self, x: usize, y: usize) -> &mut [f32] {
        let at = (y * self.width + x) * self.channels;
        &mut self.data[at..at + self.channels]
    }

    /// Bilinear filtering at texel position `t` (texel centres at i + 0.5)
    /// with clamp to edge, as a GPU computes it with f32 weights, into
    /// `out` (one value per channel).
    #[inline]
    pub fn bilinear(&self, t: [f32; 2], out: &mut [f32]) {
        let (fx, x0, x1) = split(t[0], self.width);
        let (fy, y0, y1) = split(t[1], self.height);
        let (a, b) = (self.texel(x0, y0), self.texel(x1, y0));
        let (c, d) = (self.texel(x0, y1), self.texel(x1, y1));
        for k in 0..self.channels.min(out.len()) {
            let top = a[k] + fx * (b[k] - a[k]);
            let bottom = c[k] + fx * (d[k] - c[k]);
            out[k] = top + fy * (bottom - top);
        }
    }
}

/// The weight of the upper texel and the two texel indices along an axis of
/// `n` texels at texel position `t` (clamped to the edge).
#[inline]
fn split(t: f32, n: usize) -> (f32, usize, usize) {
    let x = t - 0.5;
    let floor = x.floor();
    let last = n as i64 - 1;
    let i = floor as i64;
    (
        x - floor,
        i.clamp(0, last) as usize,
        (i + 1).clamp(0, last) as usize,
    )
}
