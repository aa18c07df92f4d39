//! The atlas: every chart of an export in one texture pair. A chart is a
//! rectangle of texels holding one grid of nodes (one side of the film,
//! today), with its own closed-form mapping ([`Mapping`]) from (thickness,
//! cos θ) to a point inside the rectangle. The shader picks the chart in
//! closed form, computes the point and does one fetch per texture; the
//! uniform array it reads ([`Atlas::uniform_f32`]) holds the atlas size, the
//! chart of each side, and three vec4 per chart (docs/gpu.md lists them).

use super::mapping::{chart_xy, Mapping};
use crate::error::{Error, Result};
use crate::render::Side;

/// Texels of edge copies around every chart. The shader clamps to a
/// chart's first and last texel centres, but a texel coordinate computed in
/// f32 near texel 8000 is off by up to 5e-4 of a texel: the filter then
/// gives the texel beyond the edge that much weight, and that texel must
/// hold the edge's own value, not a neighbouring chart's.
pub const GUTTER: usize = 1;
/// The most charts the shader's uniform array has room for.
pub const MAX_CHARTS: usize = 8;
/// vec4 per chart in the uniform array.
pub const CHART_VEC4: usize = 3;
/// vec4 in the uniform array: a header, then [`CHART_VEC4`] per chart.
pub const UNIFORM_VEC4: usize = 1 + CHART_VEC4 * MAX_CHARTS;
/// The largest texture side an atlas uses: WebGPU's default limit for 2D
/// textures, which desktop GPUs exceed.
pub const MAX_SIZE: usize = 8192;

/// A chart's parameters in the uniform array, in order (docs/gpu.md):
/// `reserved` is always 0.
pub const CHART_PARAM_NAMES: [&str; 12] = [
    "thickness_min_nm",
    "thickness_max_nm",
    "cos_min",
    "cos_max",
    "cos_crit",
    "y_crit",
    "thickness_power",
    "reserved",
    "x0",
    "y0",
    "width",
    "height",
];

/// The side's number in the shader: 0 front, 1 back.
pub fn side_index(side: Side) -> usize {
    match side {
        Side::Front => 0,
        Side::Back => 1,
    }
}

/// One rectangle of the atlas.
#[derive(Clone, Debug, PartialEq)]
pub struct Chart {
    /// The sides it serves: one, or both for a stack that reads the same
    /// from either side.
    pub sides: Vec<Side>,
    /// Its axes: domain, warps and node counts (`size_u` × `size_v`).
    pub mapping: Mapping,
    /// The texel of its first node (column, row); its gutter lies around.
    pub origin: [usize; 2],
}

impl Chart {
    /// `[x0, y0, width, height]` in texels: the nodes, gutter excluded.
    pub fn rect(&self) -> [usize; 4] {
        [
            self.origin[0],
            self.origin[1],
            self.mapping.size_u,
            self.mapping.size_v,
        ]
    }
}

/// Charts packed into one texture size, with the uniform array that
/// describes them.
#[derive(Clone, Debug, PartialEq)]
pub struct Atlas {
    /// Texels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// The charts, in the order of the uniform array.
    pub charts: Vec<Chart>,
    uniform: Vec<f32>,
}

impl Atlas {
    /// Packs the charts in one column (rows in order) or one row, whichever
    /// has the smaller area while fitting [`MAX_SIZE`], each inside its
    /// gutter. Every side must be served by exactly one chart.
    pub fn pack(charts: Vec<(Vec<Side>, Mapping)>) -> Result<Atlas> {
        if charts.is_empty() || charts.len() > MAX_CHARTS {
            return Err(Error::invalid(
                "export",
                format!(
                    "an atlas holds 1 to {MAX_CHARTS} charts, not {}",
                    charts.len()
                ),
            ));
        }
        let padded = |m: &Mapping| [m.size_u + 2 * GUTTER, m.size_v + 2 * GUTTER];
        let sizes: Vec<[usize; 2]> = charts.iter().map(|(_, m)| padded(m)).collect();
        let column = [
            sizes.iter().map(|s| s[0]).max().unwrap_or(0),
            sizes.iter().map(|s| s[1]).sum(),
        ];
        let row = [
            sizes.iter().map(|s| s[0]).sum(),
            sizes.iter().map(|s| s[1]).max().unwrap_or(0),
        ];
        let fits = |s: [usize; 2]| s[0] <= MAX_SIZE && s[1] <= MAX_SIZE;
        let in_column = match (fits(column), fits(row)) {
            (true, true) => column[0] * column[1] <= row[0] * row[1],
            (c, r) if c || r => c,
            _ => {
                return Err(Error::invalid(
                    "export",
                    format!(
                        "the charts ({}) do not fit a {MAX_SIZE}×{MAX_SIZE} texture",
                        sizes
                            .iter()
                            .map(|s| format!("{}×{}", s[0], s[1]))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                ))
            }
        };
        let [width, height] = if in_column { column } else { row };
        let mut at = 0;
        let charts: Vec<Chart> = charts
            .into_iter()
            .zip(&sizes)
            .map(|((sides, mapping), size)| {
                let origin = if in_column {
                    [GUTTER, at + GUTTER]
                } else {
                    [at + GUTTER, GUTTER]
                };
                at += size[if in_column { 1 } else { 0 }];
                Chart {
                    sides,
                    mapping,
                    origin,
                }
            })
            .collect();
        let chart_of = |side: Side| charts.iter().position(|c| c.sides.contains(&side));
        let front = chart_of(Side::Front).ok_or_else(|| {
            Error::invalid("export", "no chart serves the front side".to_string())
        })?;
        // An export without a back side answers back-side lookups from the
        // front chart (light cannot arrive from an absorbing substrate; a
        // host drawing both faces of a sheet still gets the film).
        let back = chart_of(Side::Back).unwrap_or(front);
        let mut uniform = vec![0.0f32; 4 * UNIFORM_VEC4];
        uniform[..4].copy_from_slice(&[width as f32, height as f32, front as f32, back as f32]);
        for (k, chart) in charts.iter().enumerate() {
            let at = 4 * (1 + CHART_VEC4 * k);
            let [x0, y0, w, h] = chart.rect().map(|v| v as f32);
            uniform[at..at + 8].copy_from_slice(&chart.mapping.params_f32());
            uniform[at + 8..at + 12].copy_from_slice(&[x0, y0, w, h]);
        }
        Ok(Atlas {
            width,
            height,
            charts,
            uniform,
        })
    }

    /// The uniform array as the shader reads it: [`UNIFORM_VEC4`] vec4 of
    /// f32, film.json's `uniform_f32`.
    pub fn uniform_f32(&self) -> &[f32] {
        &self.uniform
    }

    /// The chart a lookup from `side` reads: `irid_film_chart` of the shader.
    pub fn chart_of(&self, side: Side) -> usize {
        self.uniform[2 + side_index(side)] as usize
    }

    /// `irid_film_uv` of the shader, operation for operation in f32, from
    /// the uniform array: where (thickness, cos θ) lies in `chart`.
    pub fn uv(&self, chart: usize, thickness_nm: f32, cos_theta: f32) -> [f32; 2] {
        let v = &self.uniform;
        let at = 4 * (1 + CHART_VEC4 * chart);
        let params: &[f32; 8] = v[at..at + 8].try_into().expect("eight chart parameters");
        let [x, y] = chart_xy(params, thickness_nm, cos_theta);
        let [x0, y0, w, h] = [v[at + 8], v[at + 9], v[at + 10], v[at + 11]];
        let texel = [(x0 + 0.5) + x * (w - 1.0), (y0 + 0.5) + y * (h - 1.0)];
        [texel[0] / v[0], texel[1] / v[1]]
    }

    /// The two f16 textures (held in f32): each chart's node values (R and
    /// T rounded to f16, six per node, row-major over its nodes) in its
    /// rectangle, copied into its gutter; A = 1; texels in no chart 0.
    pub fn textures(&self, values: &[&[[f64; 6]]]) -> (Texture, Texture) {
        let blank = Texture {
            width: self.width,
            height: self.height,
            texels: vec![[0.0, 0.0, 0.0, 1.0]; self.width * self.height],
        };
        let (mut r, mut t) = (blank.clone(), blank);
        for (chart, nodes) in self.charts.iter().zip(values) {
            let [x0, y0, w, h] = chart.rect();
            for y in y0 - GUTTER..y0 + h + GUTTER {
                for x in x0 - GUTTER..x0 + w + GUTTER {
                    let i = (x.max(x0) - x0).min(w - 1);
                    let j = (y.max(y0) - y0).min(h - 1);
                    let v = nodes[j * w + i];
                    let at = y * self.width + x;
                    r.texels[at] = [to_f16(v[0]), to_f16(v[1]), to_f16(v[2]), 1.0];
                    t.texels[at] = [to_f16(v[3]), to_f16(v[4]), to_f16(v[5]), 1.0];
                }
            }
        }
        (r, t)
    }
}

/// Rounds to f16 (through f32, as the bake does, so every machine agrees).
pub(super) fn to_f16(v: f64) -> f32 {
    half::f16::from_f32(v as f32).to_f32()
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
    /// axis) in the RGB channels of the rectangle `[x0, y0, w, h]`: a
    /// filter whose weights are rounded to 1/256 can be off by up to this
    /// / 256 there.
    pub fn max_neighbour_step(&self, [x0, y0, w, h]: [usize; 4]) -> f32 {
        let mut worst = 0.0f32;
        for y in y0..y0 + h {
            for x in x0..x0 + w {
                let here = self.texels[y * self.width + x];
                for (nx, ny) in [(x + 1, y), (x, y + 1)] {
                    if nx < x0 + w && ny < y0 + h {
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
    use crate::export::AngleWarp;

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

    fn mapping(size_u: usize, size_v: usize) -> Mapping {
        Mapping::new(
            (10.0, 900.0),
            (0.05, 1.0),
            2.0,
            AngleWarp::Critical(0.4),
            size_u,
            size_v,
        )
    }

    #[test]
    fn nodes_land_on_their_charts_texel_centres() {
        let atlas = Atlas::pack(vec![
            (vec![Side::Front], mapping(37, 53)),
            (vec![Side::Back], mapping(20, 31)),
        ])
        .unwrap();
        // A row (61 × 55 texels) is smaller than a column (39 × 88).
        assert_eq!((atlas.width, atlas.height), (61, 55));
        assert_eq!(
            (atlas.chart_of(Side::Front), atlas.chart_of(Side::Back)),
            (0, 1)
        );
        for (k, chart) in atlas.charts.iter().enumerate() {
            let m = &chart.mapping;
            let [x0, y0, _, _] = chart.rect();
            for i in 0..m.size_u {
                for j in 0..m.size_v {
                    let uv = atlas.uv(k, m.thickness_at(i) as f32, m.cos_at(j) as f32);
                    let want = [(x0 + i) as f32 + 0.5, (y0 + j) as f32 + 0.5];
                    let texel = [uv[0] * atlas.width as f32, uv[1] * atlas.height as f32];
                    assert!((texel[0] - want[0]).abs() < 1e-4, "chart {k} u {i}");
                    assert!((texel[1] - want[1]).abs() < 2e-3, "chart {k} v {j}");
                }
            }
        }
    }

    #[test]
    fn gutters_hold_edge_copies_and_clamp_the_filter_inside_a_chart() {
        for (front, back) in [((3, 2), (2, 2)), ((6, 2), (2, 5))] {
            let atlas = Atlas::pack(vec![
                (vec![Side::Front], mapping(front.0, front.1)),
                (vec![Side::Back], mapping(back.0, back.1)),
            ])
            .unwrap();
            let values: Vec<Vec<[f64; 6]>> = atlas
                .charts
                .iter()
                .enumerate()
                .map(|(k, c)| {
                    let n = c.mapping.size_u * c.mapping.size_v;
                    (0..n).map(|i| [(10 * k + i) as f64; 6]).collect()
                })
                .collect();
            let nodes: Vec<&[[f64; 6]]> = values.iter().map(|v| v.as_slice()).collect();
            let (r, _) = atlas.textures(&nodes);
            // Every texel of a chart's padded rectangle holds its nearest
            // node; every texel outside all of them is 0.
            let mut owner = vec![None; atlas.width * atlas.height];
            for (k, chart) in atlas.charts.iter().enumerate() {
                let [x0, y0, w, h] = chart.rect();
                for y in y0 - 1..y0 + h + 1 {
                    for x in x0 - 1..x0 + w + 1 {
                        let (i, j) = (x.clamp(x0, x0 + w - 1) - x0, y.clamp(y0, y0 + h - 1) - y0);
                        assert_eq!(
                            r.texels[y * atlas.width + x][0],
                            values[k][j * w + i][0] as f32
                        );
                        owner[y * atlas.width + x] = Some(k);
                    }
                }
            }
            for (texel, owner) in r.texels.iter().zip(&owner) {
                assert!(owner.is_some() || texel[0] == 0.0);
            }
            // Far outside its domain a lookup reads the chart's corner node
            // only: the largest thickness at the smallest cos θ...
            let corner = atlas.uv(1, 1e6, -5.0);
            assert_eq!(r.sample_bilinear(corner)[0], (10 + back.0 - 1) as f32);
            // ...the smallest thickness at the largest cos θ.
            let corner = atlas.uv(0, -1.0, 5.0);
            assert_eq!(
                r.sample_bilinear(corner)[0],
                (front.0 * (front.1 - 1)) as f32
            );
            assert_eq!(r.max_neighbour_step(atlas.charts[0].rect()), front.0 as f32);
        }
    }

    #[test]
    fn a_stack_without_a_back_chart_answers_the_back_from_the_front() {
        let atlas = Atlas::pack(vec![(vec![Side::Front], mapping(4, 4))]).unwrap();
        assert_eq!(atlas.chart_of(Side::Back), 0);
        let both = Atlas::pack(vec![(vec![Side::Front, Side::Back], mapping(4, 4))]).unwrap();
        assert_eq!(both.chart_of(Side::Back), 0);
        assert_eq!(both.uniform_f32().len(), 4 * UNIFORM_VEC4);
        // Too many texels for one texture, in a column or a row.
        let big = || (vec![Side::Front], mapping(5000, 5000));
        assert!(Atlas::pack(vec![big(), big()]).is_err());
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
        assert_eq!(tex.max_neighbour_step([0, 0, w, h]), 0.5);
    }
}
