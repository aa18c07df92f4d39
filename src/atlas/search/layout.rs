//! Step 3, the layout: the bands each piece is cut into and each band's
//! scale and crowding, chosen in closed form from the probe's needs.

use super::*;

/// A chart the layout chose, and whether the target is sought on it.
pub(super) struct Planned {
    pub(super) chart: Chart,
    pub(super) sought: bool,
}

/// The bands of every piece of a side (and its corner), sized from the
/// probes.
pub(super) fn layout(
    skeleton: &Skeleton,
    goal: Goal,
    progress: &dyn Fn(&str),
) -> Result<Vec<Planned>> {
    let shares = goal.shares()?;
    let mut charts = Vec::new();
    if let Some(corner) = skeleton.corner {
        charts.push(Planned {
            chart: size_corner(skeleton, corner, shares)?,
            sought: true,
        });
    }
    let mut needs = Vec::new();
    for piece in &skeleton.pieces {
        needs.push(if piece.hi > piece.lo {
            Some(probe(skeleton, piece, shares)?)
        } else {
            None
        });
    }
    fill_untargeted(&skeleton.pieces, &mut needs);
    for (piece, needs) in skeleton.pieces.iter().zip(&needs) {
        let mut sought = true;
        let Some(needs) = needs else {
            let chart = flat_band(skeleton, piece);
            charts.push(Planned { chart, sought });
            continue;
        };
        let mut bands = cut_bands(skeleton, piece, needs);
        let predicted = texels(&bands);
        if piece.capped && predicted > CRITICAL_BAND_TEXELS {
            fit_budget(&mut bands, CRITICAL_BAND_TEXELS);
            sought = false;
        }
        progress(&format!(
            "side {} cos θ {:.4}–{:.4}: {} band(s), {predicted} texels predicted{}",
            skeleton.req.side.index(),
            piece.lo,
            piece.hi,
            bands.len(),
            if sought {
                String::new()
            } else {
                format!(
                    "; the target is not sought in this critical band, which takes {}",
                    texels(&bands)
                )
            }
        ));
        charts.extend(bands.into_iter().map(|chart| Planned { chart, sought }));
    }
    Ok(charts)
}

pub(super) fn texels(charts: &[Chart]) -> usize {
    charts.iter().map(|b| b.rect.width * b.rect.height).sum()
}

/// Scales every chart down by one factor along both axes so that together
/// they take at most about `budget` texels (at least two nodes per axis
/// that had them).
pub(super) fn fit_budget(charts: &mut [Chart], budget: usize) {
    let total = texels(charts);
    if total <= budget {
        return;
    }
    let scale = (budget as f64 / total as f64).sqrt();
    let shrink = |n: usize| ((n as f64 * scale).round() as usize).max(n.min(2));
    for chart in charts {
        chart.rect.width = shrink(chart.rect.width);
        chart.rect.height = shrink(chart.rect.height);
    }
}

/// Gives the probe rows the target does not apply to (the aliased strip)
/// the needs of the nearest rows it does apply to, so that they hold a
/// smooth continuation of the response at the resolution around them:
/// along u the nearest targeted row's (in the piece, else in the nearest
/// piece above, else below), along v the nearest targeted interval's in the
/// piece, else [`UNTARGETED_INTERVALS`] over the piece.
pub(super) fn fill_untargeted(pieces: &[Piece], needs: &mut [Option<RowNeeds>]) {
    let targeted = |list: &[f64]| list.iter().any(|&x| x > 0.0);
    let row_u = |n: &RowNeeds, j: usize| -> Vec<f64> { n.u.iter().map(|l| l[j]).collect() };
    // The u needs of the lowest (else highest) targeted row of each piece.
    let lowest: Vec<Option<Vec<f64>>> = needs
        .iter()
        .map(|n| {
            let n = n.as_ref()?;
            (0..n.c.len())
                .find(|&j| targeted(&row_u(n, j)))
                .map(|j| row_u(n, j))
        })
        .collect();
    for k in 0..needs.len() {
        let fallback = (k + 1..lowest.len())
            .chain((0..k).rev())
            .find_map(|m| lowest[m].clone());
        let Some(n) = needs[k].as_mut() else { continue };
        let rows = n.c.len();
        let nearest = |pred: &dyn Fn(usize) -> bool, j: usize| {
            (0..rows)
                .filter(|&m| pred(m))
                .min_by_key(|&m| m.abs_diff(j))
        };
        let has_u: Vec<bool> = (0..rows).map(|j| targeted(&row_u(n, j))).collect();
        for j in (0..rows).filter(|&j| !has_u[j]) {
            let source = nearest(&|m| has_u[m], j)
                .map(|m| row_u(n, m))
                .or(fallback.clone());
            for (list, v) in n.u.iter_mut().zip(source.unwrap_or_default()) {
                list[j] = v;
            }
        }
        let intervals = rows - 1;
        let has_v: Vec<bool> = (0..intervals)
            .map(|j| n.v.iter().any(|l| l[j] > 0.0))
            .collect();
        for j in (0..intervals).filter(|&j| !has_v[j]) {
            match (0..intervals)
                .filter(|&m| has_v[m])
                .min_by_key(|&m| m.abs_diff(j))
            {
                Some(m) => n.v.iter_mut().for_each(|l| l[j] = l[m]),
                None => {
                    for (o, list) in n.v.iter_mut().enumerate() {
                        let span = pieces[k]
                            .axis(pieces[k].lo, pieces[k].hi, OFFSET_CHOICES[o])
                            .span();
                        list[j] = UNTARGETED_INTERVALS / span.max(1e-300);
                    }
                }
            }
        }
    }
}

/// A two-row band for a single cos θ.
pub(super) fn flat_band(skeleton: &Skeleton, piece: &Piece) -> Chart {
    Chart {
        side: skeleton.req.side,
        optical: skeleton.optical(),
        coords: Coords::Band {
            p: band_p(skeleton, PROBE_P0_NM, piece.lo, piece.hi),
            c: CosAxis::uniform(piece.lo, piece.hi),
        },
        rect: Rect {
            x: 0,
            y: 0,
            width: PROBE_U,
            height: 2,
        },
    }
}

/// The cheapest band of `piece` over probe rows a..=b: its texels and chart,
/// with the p₀ and crowding that need the fewest.
pub(super) fn best_band(
    skeleton: &Skeleton,
    piece: &Piece,
    needs: &RowNeeds,
    a: usize,
    b: usize,
) -> (usize, Chart) {
    let optical = skeleton.optical();
    let (lo, hi) = (needs.c[a], needs.c[b]);
    let mut best: Option<(usize, Chart)> = None;
    for (k, &p0) in P0_CHOICES.iter().enumerate() {
        let p = band_p(skeleton, p0, lo, hi);
        let need_u = needs.u[k][a..=b].iter().fold(0.0f64, |m, &x| m.max(x));
        let nu = if p.hi_nm > p.lo_nm {
            nodes_for(p.span() * need_u)
        } else {
            1
        };
        let choices = if piece.warp == PieceWarp::Log {
            OFFSET_CHOICES.len()
        } else {
            1
        };
        for (o, &offset) in OFFSET_CHOICES.iter().enumerate().take(choices) {
            let c = piece.axis(lo, hi, offset);
            let need_v = needs.v[o][a..b].iter().fold(0.0f64, |m, &x| m.max(x));
            let nv = nodes_for(c.span() * need_v);
            let texels = nu.saturating_mul(nv).saturating_add(nu);
            if best.as_ref().is_none_or(|(t, _)| texels < *t) {
                let rect = Rect {
                    x: 0,
                    y: 0,
                    width: nu,
                    height: nv,
                };
                let side = skeleton.req.side;
                let coords = Coords::Band { p, c };
                best = Some((
                    texels,
                    Chart {
                        side,
                        optical,
                        coords,
                        rect,
                    },
                ));
            }
        }
    }
    best.expect("a band choice")
}

/// The bands one piece is cut into: a dynamic programme over the probe's
/// node rows as band edges.
pub(super) fn cut_bands(skeleton: &Skeleton, piece: &Piece, needs: &RowNeeds) -> Vec<Chart> {
    let rows = needs.c.len();
    let cost: Vec<Vec<usize>> = (0..rows)
        .map(|a| {
            (0..rows)
                .map(|b| {
                    if b > a {
                        best_band(skeleton, piece, needs, a, b).0
                    } else {
                        usize::MAX
                    }
                })
                .collect()
        })
        .collect();
    // best[k][b]: the cheapest cut of rows 0..=b into k + 1 bands, and the
    // start of its last band.
    let mut best = vec![vec![(usize::MAX, 0usize); rows]; MAX_BANDS_PER_PIECE];
    for b in 1..rows {
        best[0][b] = (cost[0][b], 0);
    }
    for k in 1..MAX_BANDS_PER_PIECE {
        for b in 1..rows {
            for a in 1..b {
                let total = best[k - 1][a].0.saturating_add(cost[a][b]);
                if total < best[k][b].0 {
                    best[k][b] = (total, a);
                }
            }
        }
    }
    let last = rows - 1;
    let mut k = (0..MAX_BANDS_PER_PIECE)
        .min_by_key(|&k| best[k][last].0)
        .unwrap_or(0);
    let mut cuts = vec![last];
    let mut b = last;
    while k > 0 {
        b = best[k][b].1;
        cuts.push(b);
        k -= 1;
    }
    cuts.push(0);
    cuts.reverse();
    cuts.windows(2)
        .map(|w| best_band(skeleton, piece, needs, w[0], w[1]).1)
        .collect()
}

/// The corner chart's size, from a probe of it.
pub(super) fn size_corner(skeleton: &Skeleton, corner: Chart, shares: Pair) -> Result<Chart> {
    let (n_phi, n_rho) = (33, 9);
    let (errors, _) = chart_check(skeleton, &corner, n_phi, n_rho, shares)?;
    let mut chart = corner;
    chart.rect.width = needed_nodes(n_phi, errors.0);
    chart.rect.height = needed_nodes(n_rho, errors.1);
    Ok(chart)
}
