//! Placing charts' rectangles in one texture.

/// Where each rectangle goes (x, y), and the texture's width and height.
pub type Layout = (Vec<(usize, usize)>, usize, usize);

/// Positions for rectangles of the given (width, height) texels in a
/// texture at most `max_side` texels wide and high, and the texture's
/// size: shelves of rectangles taken tallest first, for each of a few
/// texture widths, keeping the layout of fewest texels. `None` when they do
/// not fit.
pub fn pack(sizes: &[(usize, usize)], max_side: usize) -> Option<Layout> {
    let widest = sizes.iter().map(|s| s.0).max()?;
    let area: usize = sizes.iter().map(|s| s.0 * s.1).sum();
    let mut order: Vec<usize> = (0..sizes.len()).collect();
    order.sort_by_key(|&k| (std::cmp::Reverse(sizes[k].1), std::cmp::Reverse(sizes[k].0)));
    let mut best: Option<Layout> = None;
    let square = (area as f64).sqrt().ceil() as usize;
    let mut widths: Vec<usize> = [1.0, 1.25, 1.5, 2.0, 3.0]
        .iter()
        .map(|f| ((widest as f64 * f) as usize).max(widest))
        .chain([square, square * 5 / 4, square * 3 / 2])
        .filter(|&w| w >= widest && w <= max_side)
        .collect();
    // Every chart side by side, on one shelf.
    widths.push(sizes.iter().map(|s| s.0).sum::<usize>().min(max_side));
    widths.sort_unstable();
    widths.dedup();
    for width in widths {
        if width < widest {
            continue;
        }
        let mut at = vec![(0, 0); sizes.len()];
        // Shelves (y, height, width used), filled first fit.
        let mut shelves: Vec<(usize, usize, usize)> = Vec::new();
        let mut used_width = 0;
        for &k in &order {
            let (w, h) = sizes[k];
            let shelf = match shelves.iter().position(|s| s.2 + w <= width && h <= s.1) {
                Some(s) => s,
                None => {
                    let y = shelves.last().map_or(0, |s| s.0 + s.1);
                    shelves.push((y, h, 0));
                    shelves.len() - 1
                }
            };
            let s = &mut shelves[shelf];
            at[k] = (s.2, s.0);
            s.2 += w;
            used_width = used_width.max(s.2);
        }
        let (y, shelf) = shelves.last().map_or((0, 0), |s| (s.0, s.1));
        let height = y + shelf;
        if height > max_side {
            continue;
        }
        if best
            .as_ref()
            .is_none_or(|b| used_width * height < b.1 * b.2)
        {
            best = Some((at, used_width, height));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rectangles_do_not_overlap_and_fit() {
        let sizes = [(300, 20), (700, 30), (120, 9), (700, 12), (50, 50)];
        let (at, w, h) = pack(&sizes, 8192).unwrap();
        for (k, &(x, y)) in at.iter().enumerate() {
            assert!(x + sizes[k].0 <= w && y + sizes[k].1 <= h);
            for (l, &(x2, y2)) in at.iter().enumerate().skip(k + 1) {
                let apart = x + sizes[k].0 <= x2
                    || x2 + sizes[l].0 <= x
                    || y + sizes[k].1 <= y2
                    || y2 + sizes[l].1 <= y;
                assert!(apart, "{k} and {l} overlap");
            }
        }
        let area: usize = sizes.iter().map(|s| s.0 * s.1).sum();
        assert!(w * h < 2 * area, "{w}x{h} for {area} texels");
        assert!(pack(&[(9000, 2)], 8192).is_none());
    }
}
