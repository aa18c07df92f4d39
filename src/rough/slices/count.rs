//! How many slices, and how large their charts: the slice count predicted
//! from second differences between slices, the tables grown to it, the
//! charts grown where F_eff needs more nodes, packed into the atlas and
//! filled.

use super::*;

/// The charts of light from the ambient in `atlas`: the slices' charts.
pub(super) fn front_charts(atlas: &Atlas) -> Result<Vec<Chart>> {
    let charts: Vec<Chart> = atlas
        .charts
        .iter()
        .filter(|c| c.side == Side::Front)
        .copied()
        .collect();
    if charts.is_empty() {
        return Err(Error::invalid(
            "rough table",
            "the atlas has no chart of light from the ambient",
        ));
    }
    Ok(charts)
}

/// The error of slices that miss `target` when no more may be added.
pub(super) fn off_target(built: &RoughSlices, target: f64) -> Error {
    let count = built.roughness.len();
    Error::invalid(
        "rough table",
        format!(
            "{count} roughness slices of {}x{} texels are off by {:.2e} at thickness \
             {:.1} nm, cos θ {:.4}, roughness {:.3}, above the target {:.1e}",
            built.atlas.width,
            built.atlas.height,
            built.measured.max_all(),
            built.measured.worst_point[0],
            built.measured.worst_point[1],
            built.measured.worst_point[2],
            target
        ),
    )
}

/// The smooth atlas's reflectance at every node of each of `charts` (its
/// side-0 charts), row-major per chart.
pub(super) fn smooth_values(req: &SliceRequest, charts: &[Chart]) -> Vec<Vec<[f64; 3]>> {
    charts
        .iter()
        .map(|chart| {
            let r = chart.rect;
            (0..r.height)
                .flat_map(|j| (0..r.width).map(move |i| (i, j)))
                .map(|(i, j)| {
                    let v = req.image.texel(r.x + i, r.y + j);
                    [f64::from(v[0]), f64::from(v[1]), f64::from(v[2])]
                })
                .collect()
        })
        .collect()
}

/// Makes `tables` (slices 1.. of S, uniform in √roughness; slice 0 is the
/// smooth film's) those of `count` slices, (count − 1) a multiple of
/// (S − 1): the old ones keep their places, the new ones are computed.
pub(super) fn grow_tables(tables: &mut Vec<Table>, count: usize, filler: &Filler) {
    let old_count = tables.len() + 1;
    let stride = if old_count > 1 {
        (count - 1) / (old_count - 1)
    } else {
        1
    };
    let kept = |s: usize| old_count > 1 && s.is_multiple_of(stride);
    let new: Vec<usize> = (1..count).filter(|&s| !kept(s)).collect();
    let roughness: Vec<f64> = new.iter().map(|&s| slice_roughness(s, count)).collect();
    let mut computed = filler.tables(&roughness).into_iter();
    let mut old = std::mem::take(tables).into_iter();
    for s in 1..count {
        let next = if kept(s) { old.next() } else { computed.next() };
        tables.push(next.expect("a table for every slice"));
    }
}

/// The first tables: [`START_SLICES`] slices, then twice and four times as
/// many intervals until the blend meets `target`; from the blend errors of
/// the last two the count whose blend meets it (the error falling as a
/// power of the spacing, the power measured), a multiple of the last one's
/// intervals so that its slices are kept.
pub(super) fn predicted_tables(
    filler: &Filler,
    req: &SliceRequest,
    smooth0: &[Vec<[f64; 3]>],
    target: f64,
    say: &dyn Fn(String),
) -> (Vec<Table>, f64) {
    let mut tables = Vec::new();
    let mut finer = START_SLICES;
    grow_tables(&mut tables, finer, filler);
    let mut errors = vec![second_difference_error(filler, &tables, req.atlas, smooth0)];
    for _ in 0..DOUBLINGS_BEFORE_PREDICTION {
        if errors[errors.len() - 1] <= target {
            break;
        }
        finer = 2 * finer - 1;
        grow_tables(&mut tables, finer, filler);
        errors.push(second_difference_error(filler, &tables, req.atlas, smooth0));
    }
    let fine = errors[errors.len() - 1];
    if fine <= target || errors.len() < 2 {
        return (tables, fine);
    }
    let coarse = errors[errors.len() - 2];
    let predicted = predicted_count(finer, coarse, fine, target);
    say(format!(
        "{} and {finer} slices blend to {coarse:.2e} and {fine:.2e}; {predicted} predicted",
        finer / 2 + 1
    ));
    if predicted == finer {
        return (tables, fine);
    }
    grow_tables(&mut tables, predicted, filler);
    let blend = second_difference_error(filler, &tables, req.atlas, smooth0);
    (tables, blend)
}

/// The linear blend's largest error halfway between slices, estimated as
/// |F(s−1) − 2 F(s) + F(s+1)| / 8 at every node of `charts` with cos θ ≥
/// [`GRAZING_COS`] (`smooth` is slice 0 at those nodes).
pub(super) fn second_difference_error(
    filler: &Filler,
    tables: &[Table],
    atlas: &Atlas,
    smooth: &[Vec<[f64; 3]>],
) -> f64 {
    let fronts: Vec<(usize, &Chart)> = atlas
        .charts
        .iter()
        .enumerate()
        .filter(|(_, c)| c.side == Side::Front)
        .collect();
    fronts
        .par_iter()
        .zip(smooth)
        .map(|(&(owner, chart), slice0)| {
            let nodes = chart_nodes(chart);
            let stencils = filler.chart_stencils(chart);
            let mut values: Vec<Vec<[f64; 3]>> = vec![slice0.clone()];
            values.extend(tables.iter().map(|t| filler.values(t, &stencils)));
            let mut worst = 0.0f64;
            for (k, &(d, c)) in nodes.iter().enumerate() {
                if c < GRAZING_COS || atlas.chart_for(d, c, Side::Front) != Some(owner) {
                    continue;
                }
                for w in values.windows(3) {
                    let (a, b, c) = (w[0][k], w[1][k], w[2][k]);
                    for ((a, b), c) in a.iter().zip(b).zip(c) {
                        worst = worst.max((a - 2.0 * b + c).abs() / 8.0);
                    }
                }
            }
            worst
        })
        .reduce(|| 0.0, f64::max)
}

/// The slice count whose blend error meets `target`, from its errors
/// `coarse` and `fine` at (`count` − 1) / 2 and `count` − 1 intervals: the
/// error taken to fall as the spacing to the power the two show (between 1
/// and 2, the linear blend's own order), the count rounded up to a
/// multiple of `count` − 1 intervals, at most [`MAX_SLICES`].
pub(super) fn predicted_count(count: usize, coarse: f64, fine: f64, target: f64) -> usize {
    if fine <= target {
        return count;
    }
    let order = (coarse / fine).log2().clamp(1.0, 2.0);
    let factor = (fine / target).powf(1.0 / order);
    let step = count - 1;
    let multiple = (factor.ceil() as usize).max(1);
    (step * multiple + 1).min((MAX_SLICES - 1) / step * step + 1)
}

/// Rounds of growing the charts.
pub(super) const CHART_ROUNDS: usize = 3;

/// `charts` with their node counts grown until bilinear interpolation of
/// every slice's F_eff meets `target` halfway between nodes along each axis
/// (cos θ ≥ [`GRAZING_COS`]); never fewer nodes than the smooth film's.
pub(super) fn grown_charts(
    filler: &Filler,
    tables: &[Table],
    atlas: &Atlas,
    target: f64,
    max_side: usize,
) -> Vec<Chart> {
    atlas
        .charts
        .par_iter()
        .enumerate()
        .filter(|(_, c)| c.side == Side::Front)
        .map(|(k, chart)| {
            let serves = |d: f64, c: f64| atlas.chart_for(d, c, Side::Front) == Some(k);
            let mut chart = *chart;
            for _ in 0..CHART_ROUNDS {
                let (eu, ev) = midpoint_errors(filler, tables, &chart, &serves);

                let grow = |n: usize, e: f64| -> usize {
                    if e <= target || n < 2 {
                        return n;
                    }
                    let factor = (e / target).sqrt() * 1.1;
                    (1 + ((n - 1) as f64 * factor).ceil() as usize).min(max_side)
                };
                let (w, h) = (grow(chart.rect.width, eu), grow(chart.rect.height, ev));
                if (w, h) == (chart.rect.width, chart.rect.height) {
                    break;
                }
                chart.rect.width = w;
                chart.rect.height = h;
            }
            chart
        })
        .collect()
}

/// The largest error of linear interpolation halfway between neighbouring
/// nodes along u and along v of `chart`, over every slice's F_eff, where
/// `serves` says the chart is the one a reader picks (a band's nodes
/// inside a corner chart's radius are never read).
pub(super) fn midpoint_errors(
    filler: &Filler,
    tables: &[Table],
    chart: &Chart,
    serves: &dyn Fn(f64, f64) -> bool,
) -> (f64, f64) {
    let (w, h) = (chart.rect.width, chart.rect.height);
    let frac = |k: f64, n: usize| if n > 1 { k / (n - 1) as f64 } else { 0.0 };
    let point = |x: f64, y: f64| {
        let (d, c) = chart.point(x, y);
        (d.max(0.0), c.clamp(0.0, 1.0))
    };
    let nodes: Vec<Stencil> = (0..h)
        .flat_map(|j| (0..w).map(move |i| (i, j)))
        .map(|(i, j)| {
            let (d, c) = point(frac(i as f64, w), frac(j as f64, h));
            filler.stencil(d, c)
        })
        .collect();
    // (node, its neighbour, the midpoint's stencil, along u) for every
    // midpoint a reader may fetch.
    let mut checks: Vec<(usize, usize, Stencil, bool)> = Vec::new();
    for j in 0..h {
        for i in 0..w {
            if point(frac(i as f64, w), frac(j as f64, h)).1 < GRAZING_COS {
                continue;
            }
            let k = j * w + i;
            let mut check = |(d, c): (f64, f64), next: usize, along_u: bool| {
                if serves(d, c) {
                    checks.push((k, next, filler.stencil(d, c), along_u));
                }
            };
            if i + 1 < w {
                check(
                    point(frac(i as f64 + 0.5, w), frac(j as f64, h)),
                    k + 1,
                    true,
                );
            }
            if j + 1 < h {
                check(
                    point(frac(i as f64, w), frac(j as f64 + 0.5, h)),
                    k + w,
                    false,
                );
            }
        }
    }
    let off = |mid: [f64; 3], a: [f64; 3], b: [f64; 3]| {
        (0..3)
            .map(|ch| (mid[ch] - 0.5 * (a[ch] + b[ch])).abs())
            .fold(0.0, f64::max)
    };
    let (mut eu, mut ev) = (0.0f64, 0.0f64);
    for table in tables {
        let values = filler.values(table, &nodes);
        for (a, b, mid, along_u) in &checks {
            let e = off(filler.at(table, mid), values[*a], values[*b]);
            if *along_u {
                eu = eu.max(e);
            } else {
                ev = ev.max(e);
            }
        }
    }
    (eu, ev)
}

/// `charts` packed in one atlas over `thickness_nm`.
pub(super) fn packed(
    thickness_nm: (f64, f64),
    charts: Vec<Chart>,
    max_side: usize,
) -> Result<Atlas> {
    let sizes: Vec<(usize, usize)> = charts
        .iter()
        .map(|c| (c.rect.width, c.rect.height))
        .collect();
    let (places, width, height) = pack(&sizes, max_side).ok_or_else(|| {
        Error::invalid(
            "rough table",
            format!("the slices' charts do not fit in {max_side}x{max_side} texels"),
        )
    })?;
    let charts = charts
        .into_iter()
        .zip(places)
        .map(|(mut c, (x, y))| {
            c.rect.x = x;
            c.rect.y = y;
            c
        })
        .collect();
    Ok(Atlas {
        width,
        height,
        thickness_nm,
        charts,
    })
}

/// The slices' images on `atlas`: slice 0 the smooth film (the smooth
/// atlas's texels where a chart kept its size, else evaluated exactly), the
/// others from `tables`.
pub(super) fn images(
    req: &SliceRequest,
    filler: &Filler,
    tables: &[Table],
    smooth_charts: &[Chart],
    atlas: &Atlas,
) -> Result<Vec<Image>> {
    let mut slices = vec![Image::new(atlas.width, atlas.height, 3); tables.len() + 1];
    for (chart, smooth) in atlas.charts.iter().zip(smooth_charts) {
        let r = chart.rect;
        let zero: Vec<[f64; 3]> = if (r.width, r.height) == (smooth.rect.width, smooth.rect.height)
        {
            smooth_values(req, std::slice::from_ref(smooth)).remove(0)
        } else {
            req.film
                .chart(chart, r.width, r.height)?
                .into_iter()
                .map(|v| [v[0], v[1], v[2]])
                .collect()
        };
        let put = |img: &mut Image, values: &[[f64; 3]]| {
            for (k, v) in values.iter().enumerate() {
                let t = img.texel_mut(r.x + k % r.width, r.y + k / r.width);
                for ch in 0..3 {
                    t[ch] = v[ch] as f32;
                }
            }
        };
        put(&mut slices[0], &zero);
        let stencils = filler.chart_stencils(chart);
        let rest: Vec<Vec<[f64; 3]>> = tables
            .par_iter()
            .map(|t| filler.values(t, &stencils))
            .collect();
        for (img, values) in slices[1..].iter_mut().zip(rest) {
            put(img, &values);
        }
    }
    Ok(slices)
}
