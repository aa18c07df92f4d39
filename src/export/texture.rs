//! The export's textures: RGBA texels as the GPU holds them (f16 values
//! in f32), its bilinear filter, and the row check hosts use to tell a
//! flipped load from a right one.

/// Rounds to f16 (through f32, as the bake does, so every machine agrees).
pub(crate) fn to_f16(v: f64) -> f32 {
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
