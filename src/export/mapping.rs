//! The closed-form map from (thickness, cos θ) to texture coordinates that
//! `shaders/irid_film.wgsl` computes, its inverse (where the texel centres
//! sit), and the GPU's bilinear filter emulated in f32.

use serde::{Deserialize, Serialize};

/// Everything the shader's `IridParams` holds, in f64 here; the shader gets
/// each as f32 ([`Mapping::params_f32`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Mapping {
    /// The thickness range (nm) the u axis spans.
    pub thickness_min_nm: f64,
    /// See `thickness_min_nm`.
    pub thickness_max_nm: f64,
    /// The cos θ range the v axis spans.
    pub cos_min: f64,
    /// See `cos_min`.
    pub cos_max: f64,
    /// The cos θ towards which angle nodes crowd quadratically: a
    /// dense-side stack's critical angle strictly inside the range, or
    /// `cos_min` to crowd them towards grazing incidence; −1 for nodes
    /// uniform in cos θ.
    pub cos_crit: f64,
    /// The mapped angle coordinate of `cos_crit`, k / (size_v − 1): always
    /// on a node (0 when crowding towards grazing or uniform).
    pub y_crit: f64,
    /// Texels along u (thickness).
    pub size_u: usize,
    /// Texels along v (angle).
    pub size_v: usize,
    /// 1: thickness nodes uniform; 2: node i at t_min + span · (i / (N − 1))²,
    /// crowding towards t_min (where a thin film at grazing incidence
    /// changes fastest).
    pub thickness_power: f64,
}

/// How the angle nodes are placed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AngleWarp {
    /// Uniform in cos θ.
    Uniform,
    /// Crowding quadratically towards cos_min (grazing incidence).
    Grazing,
    /// A node exactly on this cos θ (a dense-side stack's critical angle),
    /// crowding quadratically towards it from both sides. Uniform when it
    /// is not strictly inside the range.
    Critical(f64),
}

/// The uniform struct's fields as the shader sees them, in declaration order.
pub const PARAM_NAMES: [&str; 9] = [
    "thickness_min_nm",
    "thickness_max_nm",
    "cos_min",
    "cos_max",
    "cos_crit",
    "y_crit",
    "size_u",
    "size_v",
    "thickness_power",
];

impl Mapping {
    /// The mapping of a `size_u` × `size_v` texture over a domain. With a
    /// critical cos θ strictly inside the cos range (and at least three
    /// angle nodes) the node k nearest its share of the range,
    /// (c_crit − c_min) / (c_max − c_min), is put on it: both sides then
    /// have the same node spacing far from it.
    pub fn new(
        thickness_nm: (f64, f64),
        cos_theta: (f64, f64),
        thickness_power: f64,
        angle: AngleWarp,
        size_u: usize,
        size_v: usize,
    ) -> Mapping {
        let (c0, c1) = cos_theta;
        let (cos_crit, y_crit) = match angle {
            AngleWarp::Critical(cc) if cc > c0 && cc < c1 && size_v >= 3 => {
                let intervals = (size_v - 1) as f64;
                let share = (cc - c0) / (c1 - c0);
                let k = (share * intervals).round().clamp(1.0, intervals - 1.0);
                (cc, k / intervals)
            }
            AngleWarp::Grazing if c1 > c0 => (c0, 0.0),
            _ => (-1.0, 0.0),
        };
        let thickness_power = if thickness_nm.1 > thickness_nm.0 {
            thickness_power
        } else {
            1.0
        };
        Mapping {
            thickness_min_nm: thickness_nm.0,
            thickness_max_nm: thickness_nm.1,
            cos_min: c0,
            cos_max: c1,
            cos_crit,
            y_crit,
            size_u: size_u.max(1),
            size_v: size_v.max(1),
            thickness_power,
        }
    }

    /// The angle warp this mapping uses.
    pub fn angle_warp(&self) -> AngleWarp {
        if self.cos_crit < 0.0 {
            AngleWarp::Uniform
        } else if self.cos_crit == self.cos_min && self.y_crit == 0.0 {
            AngleWarp::Grazing
        } else {
            AngleWarp::Critical(self.cos_crit)
        }
    }

    /// The same domain and warp with `size_u` × `size_v` texels. Doubling
    /// the intervals (2N − 1 nodes) keeps every node and the critical one.
    pub fn resized(&self, size_u: usize, size_v: usize) -> Mapping {
        let mut m = Mapping::new(
            (self.thickness_min_nm, self.thickness_max_nm),
            (self.cos_min, self.cos_max),
            self.thickness_power,
            self.angle_warp(),
            size_u,
            size_v,
        );
        // A refinement by a whole factor keeps the critical node where it
        // was (rounding anew could move it by one fine interval), so the
        // coarse nodes are exactly every factor-th fine node.
        let (old, new) = (self.size_v.saturating_sub(1), size_v.saturating_sub(1));
        if m.cos_crit == self.cos_crit && self.y_crit > 0.0 && old > 0 && new % old == 0 {
            let k = (self.y_crit * old as f64).round() * (new / old) as f64;
            m.y_crit = k / new as f64;
        }
        m
    }

    /// The thickness at texel column i.
    pub fn thickness_at(&self, i: usize) -> f64 {
        if self.size_u <= 1 {
            return self.thickness_min_nm;
        }
        let x = i as f64 / (self.size_u - 1) as f64;
        let span = self.thickness_max_nm - self.thickness_min_nm;
        if i + 1 == self.size_u {
            self.thickness_max_nm
        } else if self.thickness_power == 2.0 {
            self.thickness_min_nm + span * x * x
        } else {
            self.thickness_min_nm + span * x
        }
    }

    /// cos θ at texel row j: the inverse of the angle warp.
    pub fn cos_at(&self, j: usize) -> f64 {
        if self.size_v <= 1 {
            return self.cos_min;
        }
        let y = j as f64 / (self.size_v - 1) as f64;
        if j + 1 == self.size_v {
            return self.cos_max;
        }
        if self.cos_crit < 0.0 {
            return self.cos_min + (self.cos_max - self.cos_min) * y;
        }
        let yc = self.y_crit;
        if y >= yc {
            let s = (y - yc) / (1.0 - yc);
            self.cos_crit + (self.cos_max - self.cos_crit) * s * s
        } else {
            let s = (yc - y) / yc;
            self.cos_crit - (self.cos_crit - self.cos_min) * s * s
        }
    }

    /// The thickness nodes (nm), one per texel column.
    pub fn thickness_nodes(&self) -> Vec<f64> {
        (0..self.size_u).map(|i| self.thickness_at(i)).collect()
    }

    /// The cos θ nodes, one per texel row.
    pub fn cos_nodes(&self) -> Vec<f64> {
        (0..self.size_v).map(|j| self.cos_at(j)).collect()
    }

    /// The uniform's values as the shader receives them (f32, in
    /// [`PARAM_NAMES`] order).
    pub fn params_f32(&self) -> [f32; 9] {
        [
            self.thickness_min_nm as f32,
            self.thickness_max_nm as f32,
            self.cos_min as f32,
            self.cos_max as f32,
            self.cos_crit as f32,
            self.y_crit as f32,
            self.size_u as f32,
            self.size_v as f32,
            self.thickness_power as f32,
        ]
    }

    /// `irid_film_uv` of the shader, operation for operation in f32.
    pub fn uv(&self, thickness_nm: f32, cos_theta: f32) -> [f32; 2] {
        let [t0, t1, c0, c1, cc, yc, nu, nv, tp] = self.params_f32();
        let t_span = t1 - t0;
        let mut x = if t_span > 0.0 {
            ((thickness_nm - t0) / t_span).clamp(0.0, 1.0)
        } else {
            0.0
        };
        if tp > 1.5 {
            x = x.sqrt();
        }
        let c = cos_theta.max(c0).min(c1);
        let y = if cc < 0.0 {
            let c_span = c1 - c0;
            if c_span > 0.0 {
                (c - c0) / c_span
            } else {
                0.0
            }
        } else if c >= cc {
            yc + (1.0 - yc) * ((c - cc) / (c1 - cc)).sqrt()
        } else {
            yc - yc * ((cc - c) / (cc - c0)).sqrt()
        };
        [(x * (nu - 1.0) + 0.5) / nu, (y * (nv - 1.0) + 0.5) / nv]
    }
}

/// An RGBA texture, row-major, row 0 at v = 0 (as uploaded from the file).
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Texels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// RGBA per texel, row-major.
    pub texels: Vec<[f32; 4]>,
}

impl Texture {
    /// Bilinear filtering with clamp-to-edge at normalized coordinates, as
    /// a GPU computes it with f32 weights (lavapipe; see docs/gpu.md for
    /// GPUs whose filter weights have 8 fractional bits): texel centres at
    /// (i + 0.5) / N, weights from the fraction of u·N − 0.5.
    pub fn sample_bilinear(&self, uv: [f32; 2]) -> [f32; 4] {
        let (fx, ix) = split(uv[0], self.width);
        let (fy, iy) = split(uv[1], self.height);
        let at = |x: usize, y: usize| self.texels[y * self.width + x];
        let (a, b, c, d) = (
            at(ix.0, iy.0),
            at(ix.1, iy.0),
            at(ix.0, iy.1),
            at(ix.1, iy.1),
        );
        std::array::from_fn(|k| {
            let top = a[k] + fx * (b[k] - a[k]);
            let bottom = c[k] + fx * (d[k] - c[k]);
            top + fy * (bottom - top)
        })
    }

    /// The largest difference between neighbouring texels (along either
    /// axis) in the RGB channels: a filter whose weights are rounded to 1/256
    /// can be off by up to this / 256.
    pub fn max_neighbour_step(&self) -> f32 {
        let mut worst = 0.0f32;
        for y in 0..self.height {
            for x in 0..self.width {
                let here = self.texels[y * self.width + x];
                for (nx, ny) in [(x + 1, y), (x, y + 1)] {
                    if nx < self.width && ny < self.height {
                        let there = self.texels[ny * self.width + nx];
                        for k in 0..3 {
                            worst = worst.max((there[k] - here[k]).abs());
                        }
                    }
                }
            }
        }
        worst
    }

    /// The texel that differs most (largest RGB difference) from its mirror
    /// image about the middle row, with y in the first half: a host
    /// compares what its image loader put at (x, y) with both values to
    /// tell rows in file order from flipped ones, whatever the loader's
    /// convention. None for a single row, which has no order to get wrong.
    pub fn row_check(&self) -> Option<RowCheck> {
        let (w, h) = (self.width, self.height);
        let rgb = |x: usize, y: usize| {
            let t = self.texels[y * w + x];
            [t[0], t[1], t[2]]
        };
        let mut best: Option<(f32, RowCheck)> = None;
        for y in 0..h / 2 {
            for x in 0..w {
                let (value, mirrored) = (rgb(x, y), rgb(x, h - 1 - y));
                let gap = (0..3).fold(0.0f32, |g, k| g.max((value[k] - mirrored[k]).abs()));
                if best.as_ref().is_none_or(|(g, _)| gap > *g) {
                    let check = RowCheck {
                        x,
                        y,
                        value,
                        mirrored,
                    };
                    best = Some((gap, check));
                }
            }
        }
        best.map(|(_, check)| check)
    }
}

/// See [`Texture::row_check`]: the RGB of texel (x, y) and of texel
/// (x, height − 1 − y), rows counted in file order.
#[derive(Clone, Debug, PartialEq)]
pub struct RowCheck {
    /// Column.
    pub x: usize,
    /// Row, in the first half.
    pub y: usize,
    /// RGB at (x, y).
    pub value: [f32; 3],
    /// RGB at (x, height − 1 − y).
    pub mirrored: [f32; 3],
}

/// The filter's weight of the upper texel and the two texel indices along
/// one axis of `n` texels (clamped to the edge).
#[inline]
fn split(coord: f32, n: usize) -> (f32, (usize, usize)) {
    let x = coord * n as f32 - 0.5;
    let floor = x.floor();
    let frac = x - floor;
    let last = n as i64 - 1;
    let i0 = (floor as i64).clamp(0, last) as usize;
    let i1 = (floor as i64 + 1).clamp(0, last) as usize;
    (frac, (i0, i1))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texture(width: usize, rows: &[&[f32]]) -> Texture {
        Texture {
            width,
            height: rows.len(),
            texels: rows
                .iter()
                .flat_map(|r| r.iter().map(|&v| [v, v * 0.5, 0.25, 1.0]))
                .collect(),
        }
    }

    #[test]
    fn row_check_picks_the_texel_most_unlike_its_mirror() {
        // Rows 0 and 3 differ by 0.6 at column 1; rows 1 and 2 by 0.9 at column 0.
        let t = texture(2, &[&[0.1, 0.7], &[1.0, 0.4], &[0.1, 0.4], &[0.1, 0.1]]);
        let c = t.row_check().unwrap();
        assert_eq!((c.x, c.y), (0, 1));
        assert_eq!(c.value, [1.0, 0.5, 0.25]);
        assert_eq!(c.mirrored, [0.1, 0.05, 0.25]);
        // A symmetric texture: either order is right; the check says so by
        // two equal values.
        let c = texture(2, &[&[0.3, 0.2], &[0.3, 0.2]]).row_check().unwrap();
        assert_eq!(c.value, c.mirrored);
        assert_eq!(texture(3, &[&[0.1, 0.2, 0.3]]).row_check(), None);
    }

    #[test]
    fn nodes_land_on_texel_centres() {
        for (power, angle) in [
            (1.0, AngleWarp::Uniform),
            (2.0, AngleWarp::Critical(0.4)),
            (2.0, AngleWarp::Grazing),
            (1.0, AngleWarp::Critical(0.02)),
        ] {
            let critical = (power, angle);
            let m = Mapping::new((10.0, 900.0), (0.05, 1.0), power, angle, 37, 53);
            for i in 0..m.size_u {
                for j in 0..m.size_v {
                    let (t, c) = (m.thickness_at(i), m.cos_at(j));
                    let uv = m.uv(t as f32, c as f32);
                    let want = [
                        (i as f32 + 0.5) / m.size_u as f32,
                        (j as f32 + 0.5) / m.size_v as f32,
                    ];
                    assert!((uv[0] - want[0]).abs() < 2e-6, "{critical:?} u {i}");
                    assert!((uv[1] - want[1]).abs() < 2e-5, "{critical:?} v {j}");
                }
            }
        }
    }

    #[test]
    fn the_critical_angle_is_a_node_and_nodes_increase() {
        let m = Mapping::new(
            (0.0, 1.0),
            (0.0174, 1.0),
            2.0,
            AngleWarp::Critical(0.7303),
            2,
            65,
        );
        let nodes = m.cos_nodes();
        assert!(nodes.windows(2).all(|w| w[0] < w[1]));
        assert!(nodes.contains(&0.7303));
        // Doubling the intervals keeps every node, the critical one included.
        let fine = m.resized(3, 129);
        for (j, &c) in nodes.iter().enumerate() {
            assert!((fine.cos_at(2 * j) - c).abs() < 1e-15);
        }
        // Outside the range (or a critical angle at its edge) the warp is linear.
        let edge = Mapping::new((0.0, 1.0), (0.5, 1.0), 1.0, AngleWarp::Critical(0.5), 2, 65);
        assert_eq!(edge.cos_crit, -1.0);
        // Crowding towards grazing: quadratic from cos_min, and the warp
        // survives resizing.
        let g = Mapping::new((0.0, 1.0), (0.1, 1.0), 2.0, AngleWarp::Grazing, 5, 5);
        let want = [0.1, 0.15625, 0.325, 0.60625, 1.0];
        assert!(g
            .cos_nodes()
            .iter()
            .zip(want)
            .all(|(a, b)| (a - b).abs() < 1e-15));
        assert_eq!(g.resized(9, 9).angle_warp(), AngleWarp::Grazing);
        assert_eq!(g.thickness_nodes(), [0.0, 0.0625, 0.25, 0.5625, 1.0]);
    }

    #[test]
    fn filter_reproduces_texels_and_interpolates_linearly() {
        // A texture linear in x and y is reproduced exactly by bilinear
        // filtering anywhere inside the centres, and clamps outside.
        let (w, h) = (5, 4);
        let f = |x: f32, y: f32| 0.25 * x + 0.5 * y;
        let texels = (0..h)
            .flat_map(|y| (0..w).map(move |x| [f(x as f32, y as f32), 0.0, 0.0, 1.0]))
            .collect();
        let tex = Texture {
            width: w,
            height: h,
            texels,
        };
        for (x, y) in [(0.0, 0.0), (1.3, 2.7), (4.0, 3.0), (2.5, 0.5)] {
            let uv = [(x + 0.5) / w as f32, (y + 0.5) / h as f32];
            assert!((tex.sample_bilinear(uv)[0] - f(x, y)).abs() < 1e-6);
        }
        assert_eq!(tex.sample_bilinear([-1.0, -1.0])[0], f(0.0, 0.0));
        assert_eq!(tex.sample_bilinear([2.0, 2.0])[0], f(4.0, 3.0));
        assert_eq!(tex.max_neighbour_step(), 0.5);
    }
}
