//! One chart: a closed-form map from a film's (thickness, cos θ) to a point
//! of a rectangle of texels, its inverse (where the nodes sit), and the
//! region it serves.
//!
//! Every chart works in the varying layer's *optical thickness*
//! p = d · s(c), with s(c) = √max(1 − a (1 − c²), f²) and a = (n₀ / n_j)²
//! (real parts at a reference wavelength): p = d · Re(q_j) / Re(n_j), so
//! the layer's round-trip phase 2 k₀ q_j d is 2 k₀ n_j p whatever the
//! angle, and the fringes of a (p, cos θ) grid run along its p axis
//! instead of bending across both. f (the floor) keeps d = p / s finite for
//! a layer optically thinner than the ambient beyond its own critical
//! angle, where its fringes vanish anyway.

use serde::{Deserialize, Serialize};
use std::f64::consts::FRAC_PI_2;

use crate::sweep::Side;

/// The optical thickness factor s(c) of one side of a film.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Optical {
    /// (n₀ / n_j)², the ambient's and the varying layer's real indices at
    /// the reference wavelength.
    pub a: f64,
    /// The least s: 0 < floor ≤ 1.
    pub floor: f64,
}

/// The floor of s(c) (see [`Optical`]).
pub const OPTICAL_FLOOR: f64 = 0.2;

impl Optical {
    /// s(c) of a layer of real index `n_layer` under an ambient of real
    /// index `n_ambient`.
    pub fn new(n_ambient: f64, n_layer: f64) -> Optical {
        let a = if n_layer > 0.0 {
            (n_ambient / n_layer).powi(2)
        } else {
            0.0
        };
        Optical {
            a,
            floor: OPTICAL_FLOOR,
        }
    }

    /// s(c) = √max(1 − a (1 − c²), floor²).
    #[inline]
    pub fn s(&self, c: f64) -> f64 {
        (1.0 - self.a * (1.0 - c * c))
            .max(self.floor * self.floor)
            .sqrt()
    }
}

/// The optical-thickness axis of a band: nodes uniform in ln(1 + p / p₀)
/// (spacing growing in proportion to p + p₀: a film's colour changes
/// fastest over its first fringes and ever more slowly in higher orders),
/// or uniform in p when `p0_nm` is 0.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LogAxis {
    /// The scale p₀ (nm), or 0 for a uniform axis.
    pub p0_nm: f64,
    /// The optical thickness (nm) of the first node.
    pub lo_nm: f64,
    /// The optical thickness (nm) of the last node.
    pub hi_nm: f64,
}

impl LogAxis {
    fn warp(&self, p: f64) -> f64 {
        if self.p0_nm > 0.0 {
            (p.max(0.0) / self.p0_nm).ln_1p()
        } else {
            p
        }
    }

    fn unwarp(&self, w: f64) -> f64 {
        if self.p0_nm > 0.0 {
            self.p0_nm * w.exp_m1()
        } else {
            w
        }
    }

    /// The normalized coordinate (0 at the first node, 1 at the last) of
    /// optical thickness `p`, clamped.
    pub fn coordinate(&self, p: f64) -> f64 {
        let (lo, hi) = (self.warp(self.lo_nm), self.warp(self.hi_nm));
        if hi > lo {
            ((self.warp(p) - lo) / (hi - lo)).clamp(0.0, 1.0)
        } else {
            0.0
        }
    }

    /// The optical thickness at normalized coordinate `x`.
    pub fn at(&self, x: f64) -> f64 {
        if x >= 1.0 {
            return self.hi_nm;
        }
        if x <= 0.0 {
            return self.lo_nm;
        }
        let (lo, hi) = (self.warp(self.lo_nm), self.warp(self.hi_nm));
        self.unwarp(lo + (hi - lo) * x)
    }

    /// U(hi) − U(lo), U the warp (ln(1 + p/p₀) or p).
    pub fn span(&self) -> f64 {
        self.warp(self.hi_nm) - self.warp(self.lo_nm)
    }

    /// dU/dp at `p` (1 / nm).
    pub fn slope(&self, p: f64) -> f64 {
        if self.p0_nm > 0.0 {
            1.0 / (self.p0_nm + p.max(0.0))
        } else {
            1.0
        }
    }

    /// How fast the normalized coordinate grows with p at `p`
    /// (d coordinate / dp, in 1 / nm).
    pub fn density(&self, p: f64) -> f64 {
        let span = self.span();
        if span > 0.0 {
            self.slope(p) / span
        } else {
            0.0
        }
    }
}

/// The cos θ axis of a band over [lo, hi]: nodes uniform in
/// W(c) = σ g(|c − anchor|), σ the side of the anchor the band lies on, with
/// g(x) = ln(x + offset) (offset > 0: crowding towards the anchor on the
/// scale of the offset, as the fringes of a film near grazing incidence
/// sharpen in proportion to cos θ), √x (offset = 0: a square-root branch
/// point at the anchor, a substrate's critical angle, becomes a corner on
/// a node) or x (offset < 0: uniform).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CosAxis {
    /// cos θ of the first node.
    pub lo: f64,
    /// cos θ of the last node.
    pub hi: f64,
    /// Where the nodes crowd: at or outside [lo, hi].
    pub anchor: f64,
    /// See the type.
    pub offset: f64,
}

impl CosAxis {
    /// A uniform axis over [lo, hi].
    pub fn uniform(lo: f64, hi: f64) -> CosAxis {
        CosAxis {
            lo,
            hi,
            anchor: lo,
            offset: -1.0,
        }
    }

    fn sign(&self) -> f64 {
        if self.lo >= self.anchor {
            1.0
        } else {
            -1.0
        }
    }

    fn warp(&self, c: f64) -> f64 {
        let x = (c - self.anchor).abs();
        let g = if self.offset > 0.0 {
            (x + self.offset).ln()
        } else if self.offset == 0.0 {
            x.sqrt()
        } else {
            x
        };
        self.sign() * g
    }

    fn unwarp(&self, w: f64) -> f64 {
        let g = self.sign() * w;
        let x = if self.offset > 0.0 {
            g.exp() - self.offset
        } else if self.offset == 0.0 {
            g * g
        } else {
            g
        };
        self.anchor + self.sign() * x.max(0.0)
    }

    /// The normalized coordinate of `c`, clamped to the axis.
    pub fn coordinate(&self, c: f64) -> f64 {
        let (lo, hi) = (self.warp(self.lo), self.warp(self.hi));
        if hi > lo {
            ((self.warp(c.clamp(self.lo, self.hi)) - lo) / (hi - lo)).clamp(0.0, 1.0)
        } else {
            0.0
        }
    }

    /// cos θ at normalized coordinate `y`; the ends exactly.
    pub fn at(&self, y: f64) -> f64 {
        if y <= 0.0 {
            return self.lo;
        }
        if y >= 1.0 {
            return self.hi;
        }
        let (lo, hi) = (self.warp(self.lo), self.warp(self.hi));
        self.unwarp(lo + (hi - lo) * y).clamp(self.lo, self.hi)
    }

    /// W(hi) − W(lo), W the warp.
    pub fn span(&self) -> f64 {
        self.warp(self.hi) - self.warp(self.lo)
    }

    /// dW/dc at `c`: it depends on the anchor and offset only.
    pub fn slope(&self, c: f64) -> f64 {
        let x = (c - self.anchor).abs();
        if self.offset > 0.0 {
            1.0 / (x + self.offset)
        } else if self.offset == 0.0 {
            0.5 / x.max(1e-300).sqrt()
        } else {
            1.0
        }
    }

    /// d coordinate / dc at `c` (inside the axis).
    pub fn density(&self, c: f64) -> f64 {
        let span = self.span();
        if span > 0.0 {
            self.slope(c) / span
        } else {
            0.0
        }
    }
}

/// A chart's coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Coords {
    /// A band of cos θ: u along the optical thickness, v along cos θ. It
    /// serves cos θ in [c.lo, c.hi].
    Band {
        /// The u axis.
        p: LogAxis,
        /// The v axis.
        c: CosAxis,
    },
    /// The grazing corner of a film whose surroundings reflect nothing
    /// there (a free-standing film): near zero thickness at grazing
    /// incidence its reflectance depends on the ratio of p to cos θ, which
    /// no (p, cos θ) grid follows. Polar coordinates about the corner,
    /// P = p / scale, ρ = √(P² + c²), φ = atan2(P, c): u = φ / (π/2),
    /// v = ρ / radius, where the response is smooth. It serves ρ < radius.
    Corner {
        /// The optical thickness (nm) counted as one unit of ρ.
        scale_nm: f64,
        /// The largest ρ served.
        radius: f64,
    },
}

/// The least ρ a corner's first row of nodes is evaluated at, as a
/// fraction of its radius: the row holds the limits along each ray towards
/// the corner (at the corner itself every film reflects fully, a value no
/// neighbour approaches), and the solver resolves ratios there to 1e-9.
const CORNER_RHO_MIN: f64 = 1e-4;

/// A rectangle of texels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Rect {
    /// First column.
    pub x: usize,
    /// First row.
    pub y: usize,
    /// Columns (nodes along u), at least 2.
    pub width: usize,
    /// Rows (nodes along v), at least 2.
    pub height: usize,
}

/// One chart of an atlas.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Chart {
    /// Which side the light arrives from: the front (the stack as
    /// written) or the back (the stack reversed, cos θ in the substrate);
    /// 0 or 1 in files and the shaders' uniforms.
    pub side: Side,
    /// s(c) of that side.
    pub optical: Optical,
    /// The coordinates.
    pub coords: Coords,
    /// Where its nodes are in the atlas.
    pub rect: Rect,
}

/// The f32 values per chart in the uniform array: four vec4.
pub const PARAMS_PER_CHART: usize = 16;

impl Chart {
    /// The normalized coordinates (x, y) ∈ [0, 1]² of a film at thickness
    /// `d` (nm) and `c` = cos θ, clamped to the chart.
    pub fn xy(&self, d: f64, c: f64) -> (f64, f64) {
        match self.coords {
            Coords::Band { p: pa, c: ca } => {
                let c = c.clamp(ca.lo, ca.hi);
                (pa.coordinate(d * self.optical.s(c)), ca.coordinate(c))
            }
            Coords::Corner { scale_nm, radius } => {
                let pp = d * self.optical.s(c) / scale_nm;
                let rho = pp.hypot(c);
                let phi = pp.atan2(c);
                (
                    (phi / FRAC_PI_2).clamp(0.0, 1.0),
                    (rho / radius).clamp(0.0, 1.0),
                )
            }
        }
    }

    /// (thickness nm, cos θ) at normalized coordinates (x, y): where a node
    /// sits. Thicknesses can exceed the requested range (a chart is a
    /// rectangle in its own coordinates): they are physical all the same.
    pub fn point(&self, x: f64, y: f64) -> (f64, f64) {
        match self.coords {
            // A band of one optical thickness holds one physical thickness
            // (a table of a single thickness): p is its thickness.
            Coords::Band { p, c } if p.hi_nm <= p.lo_nm => (p.lo_nm, c.at(y)),
            Coords::Band { p, c } => {
                let c = c.at(y);
                (p.at(x) / self.optical.s(c), c)
            }
            Coords::Corner { scale_nm, radius } => {
                let rho = radius * y.max(CORNER_RHO_MIN);
                let (sin, cos) = (x.clamp(0.0, 1.0) * FRAC_PI_2).sin_cos();
                let c = rho * cos;
                let p = rho * sin * scale_nm;
                (p / self.optical.s(c), c.max(0.0))
            }
        }
    }

    /// The node (i, j) of the chart's rectangle.
    pub fn node(&self, i: usize, j: usize) -> (f64, f64) {
        let frac = |k: usize, n: usize| {
            if n > 1 {
                k as f64 / (n - 1) as f64
            } else {
                0.0
            }
        };
        self.point(frac(i, self.rect.width), frac(j, self.rect.height))
    }

    /// Whether this chart serves (d, c) on `side` by the atlas's choice
    /// rule for a corner (inside its radius). Bands are chosen by
    /// [`super::Atlas::chart_for`], which also falls back to the nearest.
    pub fn in_corner(&self, d: f64, c: f64) -> bool {
        match self.coords {
            Coords::Corner { scale_nm, radius } => {
                let pp = d * self.optical.s(c) / scale_nm;
                pp.hypot(c) < radius
            }
            Coords::Band { .. } => false,
        }
    }

    /// Its parameters are finite and within their ranges (a floor in
    /// (0, 1], increasing axes inside their domains; the side is 0 or 1 by
    /// its type, read from a file through [`Side`]'s `TryFrom<u32>`).
    pub fn check(&self) -> Result<(), String> {
        let o = self.optical;
        if !(o.a >= 0.0 && o.a.is_finite() && o.floor > 0.0 && o.floor <= 1.0) {
            return Err(format!("optical a {} floor {}", o.a, o.floor));
        }
        match self.coords {
            Coords::Band { p, c } => {
                let p_ok = p.p0_nm >= 0.0
                    && p.p0_nm.is_finite()
                    && p.lo_nm >= 0.0
                    && p.lo_nm <= p.hi_nm
                    && p.hi_nm.is_finite();
                let c_ok = c.lo >= 0.0
                    && c.lo <= c.hi
                    && c.hi <= 1.0
                    && c.anchor.is_finite()
                    && c.offset.is_finite()
                    && (c.anchor <= c.lo || c.anchor >= c.hi);
                if !(p_ok && c_ok) {
                    return Err(format!("band axes {p:?} {c:?}"));
                }
            }
            Coords::Corner { scale_nm, radius } => {
                if !(scale_nm > 0.0 && scale_nm.is_finite() && radius > 0.0 && radius.is_finite()) {
                    return Err(format!("corner scale {scale_nm} radius {radius}"));
                }
            }
        }
        Ok(())
    }

    /// The chart's uniform values (see docs/gpu.md): the rectangle, then
    /// (side, kind, a, floor), then the coordinates' parameters.
    pub fn params(&self) -> [f32; PARAMS_PER_CHART] {
        let r = self.rect;
        let (kind, q2, q3) = match self.coords {
            Coords::Band { p, c } => (
                0.0,
                [p.p0_nm, p.lo_nm, p.hi_nm, 0.0],
                [c.lo, c.hi, c.anchor, c.offset],
            ),
            Coords::Corner { scale_nm, radius } => {
                (1.0, [scale_nm, radius, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0])
            }
        };
        let mut out = [0.0f32; PARAMS_PER_CHART];
        let head = [
            r.x as f64,
            r.y as f64,
            r.width as f64,
            r.height as f64,
            f64::from(self.side.index()),
            kind,
            self.optical.a,
            self.optical.floor,
        ];
        for (o, v) in out.iter_mut().zip(head.iter().chain(&q2).chain(&q3)) {
            *o = *v as f32;
        }
        out
    }
}

/// What the shader computes, in f32, from one chart's uniform values: the
/// texel position (in texels, before dividing by the atlas size) of a film
/// at `d` nm and cos θ `c`. Operation for operation the shaders'
/// `irid_film_chart_texel` (gpu/src/generate.rs).
pub fn texel_f32(q: &[f32; PARAMS_PER_CHART], d: f32, c: f32) -> [f32; 2] {
    let s = |c: f32| (1.0 - q[6] * (1.0 - c * c)).max(q[7] * q[7]).sqrt();
    let (x, y) = if q[5] < 0.5 {
        let c = c.max(q[12]).min(q[13]);
        let p = d * s(c);
        // ln(1 + x) as the shaders write it (no log1p in WGSL or GLSL).
        let u_warp = |p: f32| {
            if q[8] > 0.0 {
                (1.0 + p.max(0.0) / q[8]).ln()
            } else {
                p
            }
        };
        let (u0, u1) = (u_warp(q[9]), u_warp(q[10]));
        let x = if u1 > u0 {
            ((u_warp(p) - u0) / (u1 - u0)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (anchor, offset) = (q[14], q[15]);
        let sign = if q[12] >= anchor { 1.0 } else { -1.0 };
        let v_warp = |c: f32| {
            let t = (c - anchor).abs();
            let g = if offset > 0.0 {
                (t + offset).ln()
            } else if offset == 0.0 {
                t.sqrt()
            } else {
                t
            };
            sign * g
        };
        let (v0, v1) = (v_warp(q[12]), v_warp(q[13]));
        let y = if v1 > v0 {
            ((v_warp(c) - v0) / (v1 - v0)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (x, y)
    } else {
        let pp = d * s(c) / q[8];
        let rho = (pp * pp + c * c).sqrt();
        // atan2(0, 0) is undefined in GLSL: the corner itself reads φ = 0.
        let phi = if rho > 0.0 { pp.atan2(c) } else { 0.0 };
        (
            (phi / std::f32::consts::FRAC_PI_2).clamp(0.0, 1.0),
            (rho / q[9]).clamp(0.0, 1.0),
        )
    };
    [q[0] + 0.5 + x * (q[2] - 1.0), q[1] + 0.5 + y * (q[3] - 1.0)]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn band(offset: f64, anchor: f64, lo: f64, hi: f64) -> Chart {
        Chart {
            side: Side::Front,
            optical: Optical::new(1.0, 1.33),
            coords: Coords::Band {
                p: LogAxis {
                    p0_nm: 150.0,
                    lo_nm: 0.0,
                    hi_nm: 1000.0,
                },
                c: CosAxis {
                    lo,
                    hi,
                    anchor,
                    offset,
                },
            },
            rect: Rect {
                x: 3,
                y: 5,
                width: 41,
                height: 17,
            },
        }
    }

    /// Every node maps back onto its own texel centre, in f64 and as the
    /// shader computes it in f32, for each kind of axis.
    #[test]
    fn nodes_land_on_texel_centres() {
        let corner = Chart {
            coords: Coords::Corner {
                scale_nm: 80.0,
                radius: 0.3,
            },
            ..band(0.0, 0.0, 0.0, 1.0)
        };
        for chart in [
            band(0.02, 0.0, 0.0, 0.4),
            band(0.0, 0.73, 0.73, 1.0),
            band(0.0, 0.73, 0.1, 0.73),
            band(-1.0, 0.2, 0.2, 0.9),
            corner,
        ] {
            let q = chart.params();
            for j in 0..chart.rect.height {
                for i in 0..chart.rect.width {
                    let (d, c) = chart.node(i, j);
                    let (x, y) = chart.xy(d, c);
                    let want = (
                        i as f64 / (chart.rect.width - 1) as f64,
                        j as f64 / (chart.rect.height - 1) as f64,
                    );
                    if !(matches!(chart.coords, Coords::Corner { .. }) && j == 0) {
                        assert!((x - want.0).abs() < 1e-9, "{chart:?} x {i} {j}");
                        assert!((y - want.1).abs() < 1e-9, "{chart:?} y {i} {j}");
                    }
                    let t = texel_f32(&q, d as f32, c as f32);
                    let centre = [
                        (chart.rect.x + i) as f32 + 0.5,
                        (chart.rect.y + j) as f32 + 0.5,
                    ];
                    // f32: a few ulps of the coordinates, times the size.
                    assert!((t[0] - centre[0]).abs() < 2e-3, "{chart:?} u {i} {j}");
                    if j > 0 {
                        assert!((t[1] - centre[1]).abs() < 2e-3, "{chart:?} v {i} {j}");
                    }
                }
            }
        }
    }

    #[test]
    fn optical_thickness_keeps_the_phase() {
        // p = d Re(q)/Re(n): for a lossless layer the round-trip phase at p
        // is the phase at normal incidence of a layer of thickness p.
        let o = Optical::new(1.0, 1.33);
        for c in [0.0, 0.3, 0.7, 1.0] {
            let q = (1.33f64 * 1.33 - (1.0 - c * c)).sqrt();
            assert!((o.s(c) - q / 1.33).abs() < 1e-15);
        }
        // A layer thinner than the ambient bottoms out at the floor.
        let thin = Optical::new(1.5, 1.0);
        assert_eq!(thin.s(0.0), OPTICAL_FLOOR);
    }
}
