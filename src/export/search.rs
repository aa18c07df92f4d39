//! The size search of one chart: the warps that need the fewest texels,
//! then grids grown until what the GPU computes from them (bilinear, f16)
//! meets the side's error target.

use super::atlas::{to_f16, Atlas, GUTTER, MAX_SIZE};
use super::mapping::{AngleWarp, Mapping};
use super::measure::Reference;
use super::{critical_cos, ExportSpec, Film};
use crate::error::{Error, Result};
use crate::render::Side;

/// The largest finite f16 value: a table holding more is not representable.
pub const F16_MAX: f64 = 65504.0;
/// |R| or |T| beyond which a gain film is taken to be at a lasing pole: a
/// hundredfold amplification is no film a renderer shows, and near a pole
/// the response is unbounded anyway.
pub const LASING_BOUND: f64 = 100.0;
/// Rounds of the size search before it gives up.
pub(super) const MAX_ROUNDS: usize = 16;
/// The most fine-grid nodes × wavelengths one round evaluates (about a
/// quarter of a minute of work on one core).
const MAX_WORK: usize = 1 << 31;
/// The largest chart side: a texture side less the gutters.
const MAX_CHART: usize = MAX_SIZE - 2 * GUTTER;

/// A chart that meets its side's target: its axes, the exact value at each
/// node (row-major, row = cos θ node) and the points it was measured at.
pub(super) struct SizedChart {
    pub(super) mapping: Mapping,
    pub(super) nodes: Vec<[f64; 6]>,
    pub(super) reference: Reference,
}

/// What a search needs of one side.
pub(super) struct SideSearch<'a> {
    /// The stack as seen from the side.
    pub(super) film: &'a Film,
    /// The spec with that stack and its varying layer.
    pub(super) spec: &'a ExportSpec,
    pub(super) side: Side,
    pub(super) target: f64,
}

impl SideSearch<'_> {
    fn gain(&self) -> bool {
        let stack = &self.film.stack;
        stack.layers.iter().any(|l| l.material.has_gain()) || stack.substrate.has_gain()
    }

    fn flat(&self) -> (bool, bool) {
        let spec = self.spec;
        (
            spec.thickness_nm.0 == spec.thickness_nm.1,
            spec.cos_theta.0 == spec.cos_theta.1,
        )
    }

    fn note(&self, progress: &dyn Fn(&str), line: &str) {
        let side = match self.side {
            Side::Front => "front",
            Side::Back => "back",
        };
        progress(&format!("{side}: {line}"));
    }

    /// Chooses the warps and the size that meets the target, from `start`
    /// (the first size tried; `None`: the warps' probe decides).
    pub(super) fn size(
        &self,
        start: Option<Mapping>,
        progress: &dyn Fn(&str),
    ) -> Result<SizedChart> {
        let (t_flat, c_flat) = self.flat();
        let gain = self.gain();
        let mut mapping = match start {
            Some(m) => m,
            None => self.choose_warps(progress)?,
        };
        let reference = Reference::new(self.film, self.spec)?;
        let waves = self.film.grid.wavelengths_nm().len();
        let target = self.target;
        for _round in 0..MAX_ROUNDS {
            let (nu, nv) = (mapping.size_u, mapping.size_v);
            let fine_map = mapping.resized(2 * nu - 1, 2 * nv - 1);
            let work = fine_map.size_u * fine_map.size_v * waves;
            if nu > MAX_CHART || nv > MAX_CHART || work > MAX_WORK {
                break;
            }
            let fine = self.film.eval(&fine_map)?;
            check_representable(&fine_map, &fine, gain)?;
            let [e_u, e_v, e_c] = midpoint_errors(&mapping, &fine);
            let coarse: Vec<[f64; 6]> = (0..nv)
                .flat_map(|j| (0..nu).map(move |i| (i, j)))
                .map(|(i, j)| fine[2 * j * fine_map.size_u + 2 * i])
                .collect();
            let budget = budget_after_f16_rounding(&coarse, target)?;
            self.note(
                progress,
                &format!(
                    "{nu}×{nv}: midpoint error {e_u:.2e} (u) {e_v:.2e} (v) {e_c:.2e} (centre)"
                ),
            );
            let (gu, gv) = if e_u.max(e_v).max(e_c) <= target {
                let measured = measure_alone(&mapping, &coarse, &reference)?;
                self.note(
                    progress,
                    &format!(
                        "{nu}×{nv}: {} random points, max error {measured:.2e}",
                        self.spec.points
                    ),
                );
                if measured <= target {
                    return Ok(SizedChart {
                        mapping,
                        nodes: coarse,
                        reference,
                    });
                }
                // A feature between the midpoints: refine both axes.
                let grow = growth_for_measured(measured, target);
                (grow, grow)
            } else {
                growth_for_midpoint_errors([e_u, e_v, e_c], budget)
            };
            mapping = mapping.resized(grown(nu, gu, t_flat), grown(nv, gv, c_flat));
        }
        Err(Error::invalid(
            "max-error",
            format!(
                "{target} is not reached within {MAX_CHART}×{MAX_CHART} texels{}",
                if gain {
                    " (a gain film near a lasing pole? narrow --thickness or --angles)"
                } else {
                    " (narrow --thickness or --angles)"
                }
            ),
        ))
    }

    /// The axis warps: a dense-side stack's critical angle inside the range
    /// always gets its node; otherwise each of uniform and crowded
    /// (thickness towards its minimum, angle towards grazing) is tried on a
    /// 129 × 129 grid, and the pair whose midpoint errors predict the fewest
    /// texels (bilinear error falls as h²) wins.
    fn choose_warps(&self, progress: &dyn Fn(&str)) -> Result<Mapping> {
        const PROBE: usize = 129;
        let spec = self.spec;
        let (t_flat, c_flat) = self.flat();
        let size = |flat: bool| if flat { 1 } else { PROBE };
        let critical = critical_cos(&self.film.stack)
            .filter(|&cc| cc > spec.cos_theta.0 && cc < spec.cos_theta.1);
        let angles = match critical {
            Some(cc) => vec![AngleWarp::Critical(cc)],
            None if c_flat => vec![AngleWarp::Uniform],
            None => vec![AngleWarp::Uniform, AngleWarp::Grazing],
        };
        let powers: &[f64] = if t_flat { &[1.0] } else { &[1.0, 2.0] };
        let candidates: Vec<Mapping> = powers
            .iter()
            .flat_map(|&p| {
                angles.iter().map(move |&a| {
                    Mapping::new(
                        spec.thickness_nm,
                        spec.cos_theta,
                        p,
                        a,
                        size(t_flat),
                        size(c_flat),
                    )
                })
            })
            .collect();
        if candidates.len() == 1 {
            return Ok(candidates[0].resized(start_size(t_flat), start_size(c_flat)));
        }
        let share = 0.5 * self.target;
        let gain = self.gain();
        let predicted = |m: &Mapping| -> Result<f64> {
            let fine_map = m.resized(2 * m.size_u - 1, 2 * m.size_v - 1);
            let fine = self.film.eval(&fine_map)?;
            check_representable(&fine_map, &fine, gain)?;
            let [e_u, e_v, e_c] = midpoint_errors(m, &fine);
            let e_u = e_u.max(0.5 * e_c);
            let e_v = e_v.max(0.5 * e_c);
            let n = |e: f64, flat: bool| {
                if flat {
                    1.0
                } else {
                    (PROBE as f64 * (e / share).sqrt()).max(2.0)
                }
            };
            let texels = n(e_u, t_flat) * n(e_v, c_flat);
            self.note(
                progress,
                &format!(
                    "warp: thickness power {}, angle {:?}: midpoint error {e_u:.2e} (u) {e_v:.2e} (v), predicts {texels:.0} texels",
                    m.thickness_power,
                    m.angle_warp()
                ),
            );
            Ok(texels)
        };
        let mut best = (f64::INFINITY, candidates[0]);
        for m in &candidates {
            let texels = predicted(m)?;
            if texels < best.0 {
                best = (texels, *m);
            }
        }
        Ok(best.1.resized(start_size(t_flat), start_size(c_flat)))
    }
}

/// The largest error over channels of a chart alone in its atlas (gutter
/// included), sampled as the GPU does, at the reference points.
fn measure_alone(mapping: &Mapping, nodes: &[[f64; 6]], reference: &Reference) -> Result<f64> {
    let atlas = Atlas::pack(vec![(vec![Side::Front], *mapping)])?;
    let (r, t) = atlas.textures(&[nodes]);
    Ok(reference
        .measure(|th, c| sample(&atlas, &r, &t, 0, th, c))
        .max_all())
}

/// What the GPU computes from `chart` of the atlas textures `r`, `t` at
/// (thickness, cos θ): R and T, six values.
pub(super) fn sample(
    atlas: &Atlas,
    r: &super::Texture,
    t: &super::Texture,
    chart: usize,
    thickness_nm: f32,
    cos_theta: f32,
) -> [f64; 6] {
    let uv = atlas.uv(chart, thickness_nm, cos_theta);
    let (a, b) = (r.sample_bilinear(uv), t.sample_bilinear(uv));
    [a[0], a[1], a[2], b[0], b[1], b[2]].map(f64::from)
}

/// The growth of both axes when the random points measure `measured`
/// above `target` though every midpoint met it: a feature between them.
pub(super) fn growth_for_measured(measured: f64, target: f64) -> f64 {
    ((measured / target).sqrt() * 1.1).clamp(1.15, 2.0)
}

/// Fails, naming where, when a value is not finite or beyond f16, or, for
/// a gain film, beyond [`LASING_BOUND`]: its range reaches (or crosses) a
/// lasing pole.
fn check_representable(mapping: &Mapping, values: &[[f64; 6]], gain: bool) -> Result<()> {
    let bound = if gain { LASING_BOUND } else { F16_MAX };
    let Some(k) = values
        .iter()
        .position(|v| v.iter().any(|x| x.is_nan() || x.abs() > bound))
    else {
        return Ok(());
    };
    let (i, j) = (k % mapping.size_u, k / mapping.size_u);
    let at = format!(
        "thickness {:.3} nm, cos θ {:.6}",
        mapping.thickness_at(i),
        mapping.cos_at(j)
    );
    Err(if gain {
        Error::invalid(
            "gain film",
            format!("R or T exceeds {LASING_BOUND} or is not finite at {at}: the range reaches a lasing pole; narrow --thickness or --angles"),
        )
    } else {
        Error::invalid("export", format!("R or T is not finite at {at}"))
    })
}

/// Interpolation error of the coarse nodes (even indices of `fine`, rounded
/// to f16) at the fine grid's midpoints: along u only, along v only, and at
/// cell centres.
fn midpoint_errors(coarse: &Mapping, fine: &[[f64; 6]]) -> [f64; 3] {
    let (nu, nv) = (2 * coarse.size_u - 1, 2 * coarse.size_v - 1);
    let at = |i: usize, j: usize| &fine[j * nu + i];
    let stored = |i: usize, j: usize| at(i, j).map(|x| f64::from(to_f16(x)));
    let mut worst = [0.0f64; 3];
    for j in 0..nv {
        for i in 0..nu {
            let kind = match (i % 2, j % 2) {
                (0, 0) => continue,
                (1, 0) => 0,
                (0, 1) => 1,
                _ => 2,
            };
            let (i0, i1) = (i - i % 2, i + i % 2);
            let (j0, j1) = (j - j % 2, j + j % 2);
            let (a, b, c, d) = (
                stored(i0, j0),
                stored(i1, j0),
                stored(i0, j1),
                stored(i1, j1),
            );
            let exact = at(i, j);
            for k in 0..6 {
                let interp = 0.25 * (a[k] + b[k] + c[k] + d[k]);
                worst[kind] = worst[kind].max((interp - exact[k]).abs());
            }
        }
    }
    worst
}

/// What remains of `target` for the bilinear error once f16 has rounded
/// the largest of `values`: f16 rounds each value by up to half its ulp, a
/// part of the budget no grid can buy back.
fn budget_after_f16_rounding(values: &[[f64; 6]], target: f64) -> Result<f64> {
    let largest = values
        .iter()
        .flat_map(|v| v.iter())
        .fold(0.0f64, |a, &b| a.max(b.abs()));
    let rounding = f16_half_ulp(largest);
    if rounding >= 0.9 * target {
        return Err(Error::invalid(
            "max-error",
            format!(
                "{target} cannot be met with f16 texels: values reach {largest:.3}, which f16 rounds by up to {rounding:.2e}"
            ),
        ));
    }
    Ok(target - rounding)
}

/// The growth of each axis (u, v) for midpoint errors (u, v, centre) over
/// `budget`. Bilinear error falls as h²: each axis grows by what its own
/// midpoint error asks, aiming at half the budget each.
fn growth_for_midpoint_errors([e_u, e_v, e_c]: [f64; 3], budget: f64) -> (f64, f64) {
    let share = 0.5 * budget;
    let factor = |e: f64| ((e / share).sqrt() * 1.1).clamp(1.0, 4.0);
    let (gu, gv) = (factor(e_u), factor(e_v));
    if gu == 1.0 && gv == 1.0 {
        // Only cell centres fail: both axes a little.
        let g = factor(e_c).max(1.15);
        return (g, g);
    }
    (gu, gv)
}

/// The first size the search tries along an axis.
fn start_size(flat: bool) -> usize {
    if flat {
        1
    } else {
        17
    }
}

/// A new axis size: `n` grown by `factor` (by at least one texel when
/// growing), 1 for a flat axis.
pub(super) fn grown(n: usize, factor: f64, flat: bool) -> usize {
    if flat {
        return 1;
    }
    if factor <= 1.0 {
        return n;
    }
    let intervals = ((n - 1) as f64 * factor).ceil() as usize;
    (intervals + 1).max(n + 1)
}

/// Half an f16 ulp at magnitude `v` (normal range).
fn f16_half_ulp(v: f64) -> f64 {
    if v < 6.2e-5 {
        return 2f64.powi(-25);
    }
    let exponent = v.log2().floor();
    2f64.powf(exponent - 11.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_ulp_matches_f16_rounding() {
        for v in [0.3f64, 0.9, 1.0, 1.7, 3.0, 100.0] {
            let bound = f16_half_ulp(v);
            let mut worst = 0.0f64;
            for k in 0..2000 {
                let x = v * (1.0 + k as f64 * 1e-6);
                if f16_half_ulp(x) == bound {
                    worst = worst.max((f64::from(to_f16(x)) - x).abs());
                }
            }
            // Through f32 first: that rounding (up to 6e-8 relative) adds on.
            assert!(
                worst <= bound + 1e-7 * v && worst > 0.5 * bound,
                "{v}: {worst} vs {bound}"
            );
        }
    }
}
