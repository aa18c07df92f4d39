//! Tables against their error: for each bench stack and table kind, the
//! grid layout (format versions 2 and 3) beside the atlas (version 4),
//! baked for the same error target over the same domain (the stack's
//! thickness range, every angle): nodes, bytes, build time and the error
//! measured against the solver at random points.

use std::time::Instant;

use super::stacks::BenchStack;
use crate::error::Result;
use crate::lut::{bake, validate, BakeSpec, Kind, Layout, Resolution};

/// The error targets: rgb tables to 1e-3 (the `irid bake` default),
/// spectral ones to 1e-2.
pub const RGB_TARGET: f64 = 1e-3;
/// See [`RGB_TARGET`].
pub const SPECTRAL_TARGET: f64 = 1e-2;
/// The wavelengths a spectral table spans (what spectral renderers sample).
pub const SPECTRAL_RANGE_NM: (f64, f64) = (360.0, 830.0);

/// What one bake gave.
#[derive(Clone, Debug, PartialEq)]
pub struct TableFigures {
    /// Nodes stored (texels × wavelength nodes for a spectral atlas;
    /// thickness × cos θ [× wavelength] nodes for a grid).
    pub nodes: usize,
    /// The table's file, f32.
    pub bytes: u64,
    /// Wall time of the bake (its own validation included).
    pub build_s: f64,
    /// The largest absolute error at the bench's random points where the
    /// table's target applies (outside an atlas's aliased strip and
    /// dispersive critical band).
    pub max_abs: f64,
    /// The largest over every point, those regions included.
    pub max_abs_all: f64,
    /// cos θ below which the table does not follow the fringes (0: none).
    pub aliased_below: f64,
}

/// One table of the comparison.
#[derive(Clone, Debug, PartialEq)]
pub struct TableRow {
    /// The bench stack's name.
    pub stack: &'static str,
    /// rgb or spectral.
    pub kind: Kind,
    /// grid or atlas.
    pub layout: Layout,
    /// The error target.
    pub target: f64,
    /// The figures, or why the bake stopped (and after how long).
    pub outcome: std::result::Result<TableFigures, (String, f64)>,
}

/// The spec of a table of `kind` in `layout` for `bench` over every angle.
pub fn spec(bench: &BenchStack, kind: Kind, layout: Layout) -> BakeSpec {
    let mut spec = bench.bake_spec(2, 2, false);
    spec.kind = kind;
    spec.layout = layout;
    spec.resolution = Resolution::MaxError(match kind {
        Kind::Rgb => RGB_TARGET,
        Kind::Spectral => SPECTRAL_TARGET,
    });
    spec.wavelength_nm = SPECTRAL_RANGE_NM;
    // As `irid bake`: the bake's own validation is part of its search.
    spec.validation_points = 20_000;
    spec
}

/// Bakes and measures every stack's tables of both kinds in both layouts,
/// each measured at `points` random points (seed `seed`); `dir` holds the
/// files while their size is read. `progress` gets a line per table.
pub fn run(
    stacks: &[BenchStack],
    points: usize,
    seed: u64,
    dir: &std::path::Path,
    progress: &dyn Fn(&str),
) -> Result<Vec<TableRow>> {
    std::fs::create_dir_all(dir).map_err(|e| crate::error::Error::io(dir, e))?;
    let mut rows = Vec::new();
    for bench in stacks {
        for kind in [Kind::Rgb, Kind::Spectral] {
            for layout in [Layout::Grid, Layout::Atlas] {
                let spec = spec(bench, kind, layout);
                let target = match spec.resolution {
                    Resolution::MaxError(e) => e,
                    Resolution::Nodes { .. } => f64::NAN,
                };
                let started = Instant::now();
                let outcome = match bake(&spec) {
                    Ok(lut) => {
                        let build_s = started.elapsed().as_secs_f64();
                        let path = dir.join(format!("{}-{kind}-{layout:?}.exr", bench.name));
                        lut.write(&path)?;
                        let bytes = std::fs::metadata(&path)
                            .map_err(|e| crate::error::Error::io(&path, e))?
                            .len();
                        let _ = std::fs::remove_file(&path);
                        let stats = validate(&lut, points, seed)?;
                        let all = stats.figures.max_all();
                        let resolved = stats
                            .regions
                            .iter()
                            .find(|r| r.name == "resolved")
                            .map_or(all, |r| r.max_abs);
                        let h = lut.header();
                        let nodes = match &h.atlas {
                            Some(t) => {
                                t.atlas.width
                                    * t.atlas.height
                                    * h.axes.get(2).map_or(1, |w| w.nodes.len())
                            }
                            None => h.axes.iter().map(|a| a.nodes.len()).product(),
                        };
                        Ok(TableFigures {
                            nodes,
                            bytes,
                            build_s,
                            max_abs: resolved,
                            max_abs_all: all,
                            aliased_below: h.atlas.as_ref().map_or(0.0, |t| t.aliased_below_cos),
                        })
                    }
                    Err(e) => Err((e.to_string(), started.elapsed().as_secs_f64())),
                };
                progress(&match &outcome {
                    Ok(f) => format!(
                        "  {} {kind} {layout:?}: {} nodes, {} bytes, {:.2} s, max {:.2e}",
                        bench.name, f.nodes, f.bytes, f.build_s, f.max_abs
                    ),
                    Err((e, s)) => format!("  {} {kind} {layout:?}: {e} ({s:.1} s)", bench.name),
                });
                rows.push(TableRow {
                    stack: bench.name,
                    kind,
                    layout,
                    target,
                    outcome,
                });
            }
        }
    }
    Ok(rows)
}

/// The comparison as a Markdown table: per stack and kind, the grid and
/// the atlas side by side.
pub fn markdown(rows: &[TableRow], points: usize) -> String {
    let mut s = String::from(
        "| stack | kind | target | grid nodes | grid bytes | grid s | grid max err | atlas nodes | atlas bytes | atlas s | atlas max err | aliased below cos θ |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for pair in rows.chunks(2) {
        let [grid, atlas] = pair else { continue };
        let cells = |r: &TableRow| -> [String; 4] {
            match &r.outcome {
                Ok(f) => [
                    f.nodes.to_string(),
                    f.bytes.to_string(),
                    format!("{:.2}", f.build_s),
                    format!("{:.2e}", f.max_abs),
                ],
                Err((_, secs)) => [
                    "not reached".into(),
                    "–".into(),
                    format!("{secs:.1}"),
                    "–".into(),
                ],
            }
        };
        let (g, a) = (cells(grid), cells(atlas));
        let aliased = match &atlas.outcome {
            Ok(f) if f.aliased_below > 0.0 => format!("{:.4}", f.aliased_below),
            Ok(_) => "0".into(),
            Err(_) => "–".into(),
        };
        s.push_str(&format!(
            "| {} | {} | {:e} | {} | {} | {} | {} | {} | {} | {} | {} | {aliased} |\n",
            grid.stack, grid.kind, grid.target, g[0], g[1], g[2], g[3], a[0], a[1], a[2], a[3]
        ));
    }
    s.push_str(&format!(
        "\nErrors: largest absolute error in any channel at {points} random points against the solver, where the table's target applies (an atlas's aliased strip, below the last column, excluded). Bytes: the f32 OpenEXR file. A grid that is \"not reached\" stopped at the size limits after the seconds shown.\n"
    ));
    for r in rows {
        if let Err((e, _)) = &r.outcome {
            s.push_str(&format!("\n- {} {} {:?}: {e}", r.stack, r.kind, r.layout));
        }
    }
    s.push('\n');
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Over a short thickness range both layouts of both kinds bake, meet
    /// their targets at the bench's points, and pair up in the report.
    #[test]
    fn grid_beside_atlas_for_each_kind() {
        let mut bench = super::super::stacks::find("absorbing").unwrap().unwrap();
        bench.thickness_range_nm = (0.0, 150.0);
        let dir = std::env::temp_dir().join(format!("irid-tables-test-{}", std::process::id()));
        let rows = run(&[bench], 2000, 3, &dir, &|_| {}).unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        let order: Vec<(Kind, Layout)> = rows.iter().map(|r| (r.kind, r.layout)).collect();
        assert_eq!(
            order,
            [
                (Kind::Rgb, Layout::Grid),
                (Kind::Rgb, Layout::Atlas),
                (Kind::Spectral, Layout::Grid),
                (Kind::Spectral, Layout::Atlas)
            ]
        );
        for r in &rows {
            let f = r.outcome.as_ref().unwrap();
            assert!(f.nodes > 0 && f.bytes > 0 && f.build_s > 0.0, "{r:?}");
            assert!(f.max_abs <= r.target, "{r:?}");
        }
        let md = markdown(&rows, 2000);
        let lines: Vec<&str> = md
            .lines()
            .filter(|l| l.starts_with("| absorbing"))
            .collect();
        assert_eq!(lines.len(), 2, "{md}");
        assert!(lines[1].contains("| spectral |"), "{md}");
    }
}
