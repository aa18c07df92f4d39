//! The rough table's bake beside the smooth one: for each bench stack, the
//! rgb atlas (what `irid bake` writes) and then the rough table of the same
//! film (`irid bake --rough`, its own smooth atlas included), timed in the
//! same run, with the rough table's size and its error measured against
//! irid's rough reflectance at random points.

use std::time::Instant;

use super::stacks::BenchStack;
use super::tables::{spec, RGB_TARGET};
use crate::error::Result;
use crate::lut::rough::bake_rough;
use crate::lut::{bake, Kind, Layout};

/// The rough tables' error target (the issue's: 2e-3).
pub const ROUGH_TARGET: f64 = 2e-3;

/// What one stack's smooth and rough bakes gave.
#[derive(Clone, Debug, PartialEq)]
pub struct RoughRow {
    /// The bench stack's name.
    pub stack: &'static str,
    /// Wall time of the smooth rgb atlas bake (to [`RGB_TARGET`]).
    pub smooth_s: f64,
    /// Wall time of the rough bake, its smooth atlas included, or why it
    /// stopped.
    pub rough: std::result::Result<RoughFigures, String>,
}

/// A rough table's figures.
#[derive(Clone, Debug, PartialEq)]
pub struct RoughFigures {
    /// Wall time of `bake_rough`.
    pub build_s: f64,
    /// Slices, and one slice's texels.
    pub slices: usize,
    /// Texels of one slice.
    pub texels: usize,
    /// The measured error (cos θ ≥ the grazing strip), largest channel.
    pub max_abs: f64,
    /// The same below the grazing strip.
    pub grazing_max_abs: f64,
    /// Points of the measurement.
    pub points: usize,
}

/// Bakes every stack's smooth rgb atlas and its rough table, timed (a
/// stack whose smooth atlas cannot be made, such as the gain film's lasing
/// pole, gets its reason instead). `progress` gets a line per stack.
pub fn run(stacks: &[BenchStack], progress: &dyn Fn(&str)) -> Result<Vec<RoughRow>> {
    let mut rows = Vec::new();
    for bench in stacks {
        let mut spec = spec(bench, Kind::Rgb, Layout::Atlas);
        spec.validation_points = 0;
        let started = Instant::now();
        let smooth = bake(&spec);
        let smooth_s = started.elapsed().as_secs_f64();
        let started = Instant::now();
        let rough = smooth
            .map_err(|e| format!("no smooth atlas: {e}"))
            .and_then(|_| bake_rough(&spec, ROUGH_TARGET, &|_| {}).map_err(|e| e.to_string()))
            .map(|t| {
                let s = t.slices();
                RoughFigures {
                    build_s: started.elapsed().as_secs_f64(),
                    slices: s.slices.len(),
                    texels: s.atlas.width * s.atlas.height,
                    max_abs: s.measured.max_all(),
                    grazing_max_abs: s.grazing.max_all(),
                    points: s.measured.points,
                }
            });
        progress(&match &rough {
            Ok(f) => format!(
                "  {}: smooth {smooth_s:.2} s, rough {:.2} s ({} slices), max {:.2e}",
                bench.name, f.build_s, f.slices, f.max_abs
            ),
            Err(e) => format!("  {}: rough table not made: {e}", bench.name),
        });
        rows.push(RoughRow {
            stack: bench.name,
            smooth_s,
            rough,
        });
    }
    Ok(rows)
}

/// The rows as a Markdown table.
pub fn markdown(rows: &[RoughRow]) -> String {
    let mut s = String::from(
        "| stack | smooth atlas s | rough table s | ratio | slices | texels per slice | rough max err | grazing max err |\n|---|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for r in rows {
        let smooth = format!("{:.2}", r.smooth_s);
        match &r.rough {
            Ok(f) => s.push_str(&format!(
                "| {} | {smooth} | {:.2} | {:.1} | {} | {} | {:.2e} | {:.2e} |\n",
                r.stack,
                f.build_s,
                f.build_s / r.smooth_s,
                f.slices,
                f.texels,
                f.max_abs,
                f.grazing_max_abs
            )),
            Err(_) => s.push_str(&format!(
                "| {} | {smooth} | not made | – | – | – | – | – |\n",
                r.stack
            )),
        }
    }
    let points = rows
        .iter()
        .find_map(|r| r.rough.as_ref().ok().map(|f| f.points))
        .unwrap_or(0);
    s.push_str(&format!(
        "\nSmooth: the rgb atlas to {RGB_TARGET:e} (`irid bake`, without its validation). Rough: `irid bake --rough` to {ROUGH_TARGET:e}, its smooth atlas included. Errors: largest absolute error in any channel against irid's rough reflectance at {points} random points (cos θ ≥ 0.02; the grazing strip below it apart, where the target is not sought).\n"
    ));
    for r in rows {
        if let Err(e) = &r.rough {
            s.push_str(&format!("\n- {}: {e}", r.stack));
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A short range of the absorbing film: both bakes run, the rough
    /// table meets its target, and the report has its row.
    #[test]
    fn rough_beside_smooth() {
        let mut bench = super::super::stacks::find("absorbing").unwrap().unwrap();
        bench.thickness_range_nm = (0.0, 150.0);
        let rows = run(&[bench], &|_| {}).unwrap();
        let f = rows[0].rough.as_ref().unwrap();
        assert!(rows[0].smooth_s > 0.0 && f.build_s > 0.0 && f.slices >= 2);
        assert!(f.max_abs <= ROUGH_TARGET && f.points > 0, "{f:?}");
        let md = markdown(&rows);
        assert_eq!(
            md.lines().filter(|l| l.starts_with("| absorbing")).count(),
            1,
            "{md}"
        );
    }
}
