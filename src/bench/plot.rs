//! The speed-vs-error picture: one point per method, time per shading
//! evaluation against mean CIEDE2000, both axes logarithmic.
//!
//! Drawn with plotters' bitmap backend and an embedded font (DejaVu Sans,
//! cut to ASCII; licence beside it), so it needs no system font libraries,
//! and encoded with the `image` crate.

use std::io::Cursor;
use std::ops::Range;
use std::path::Path;
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};

use crate::error::{Error, Result};

static FONT: &[u8] = include_bytes!("font/DejaVuSans-subset.ttf");
const FONT_NAME: &str = "irid-sans";

/// One method's point on the speed-vs-error plot.
#[derive(Clone, Debug)]
pub struct PlotPoint {
    /// The method's name, written beside its point.
    pub label: String,
    /// Selects the colour: methods of one family share it.
    pub family: usize,
    /// Time per shading evaluation in nanoseconds (x axis, logarithmic).
    pub ns_per_eval: f64,
    /// Mean CIEDE2000 against the exact method (y axis, logarithmic;
    /// values below the plot's floor are drawn at the floor).
    pub mean_de2000: f64,
}

const FAMILY_COLORS: [RGBColor; 4] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
];

/// Draws the plot into a PNG at `path` (atomically). Errors below `floor`
/// (the exact method's zero) are drawn at the floor; `floor_note` says so
/// in the caption.
pub fn speed_vs_error_png(
    path: &Path,
    points: &[PlotPoint],
    families: &[&str],
    floor: f64,
    caption: &str,
) -> Result<()> {
    static REGISTER: Once = Once::new();
    let mut font_error = None;
    REGISTER.call_once(|| {
        if register_font(FONT_NAME, FontStyle::Normal, FONT).is_err() {
            font_error = Some(());
        }
    });
    if font_error.is_some() {
        return Err(Error::invalid(
            "plot",
            "the embedded font could not be read",
        ));
    }
    if points.is_empty() {
        return Err(Error::invalid("plot", "no points to draw"));
    }
    let (w, h) = (1200u32, 760u32);
    let mut buf = vec![0u8; (w * h * 3) as usize];
    draw(&mut buf, (w, h), points, families, floor, caption)
        .map_err(|e| Error::invalid("plot", e.to_string()))?;
    let img = image::RgbImage::from_raw(w, h, buf)
        .ok_or_else(|| Error::invalid("plot", "pixel buffer has the wrong size"))?;
    let mut png = Cursor::new(Vec::new());
    img.write_to(&mut png, image::ImageFormat::Png)
        .map_err(|e| Error::invalid("plot", e.to_string()))?;
    crate::atomic::write(path, png.get_ref())
}

fn draw(
    buf: &mut [u8],
    size: (u32, u32),
    points: &[PlotPoint],
    families: &[&str],
    floor: f64,
    caption: &str,
) -> std::result::Result<(), Box<dyn std::error::Error>> {
    let root = BitMapBackend::with_buffer(buf, size).into_drawing_area();
    root.fill(&WHITE)?;
    let y_of = |p: &PlotPoint| p.mean_de2000.max(floor);
    let (mut x_lo, mut x_hi, mut y_hi) = (f64::INFINITY, 0.0f64, floor);
    for p in points {
        x_lo = x_lo.min(p.ns_per_eval);
        x_hi = x_hi.max(p.ns_per_eval);
        y_hi = y_hi.max(y_of(p));
    }
    // Half a decade of margin on each side so labels stay inside.
    let x_range = (x_lo / 2.0)..(x_hi * 3.0);
    let y_range = (floor / 3.0)..(y_hi * 3.0);
    let font = |px: u32| (FONT_NAME, px).into_font();
    let legend_width = 250;
    let mut chart = ChartBuilder::on(&root)
        .caption(caption, font(20))
        .margin(18)
        .margin_right(legend_width)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d(x_range.log_scale(), y_range.log_scale())?;
    chart
        .configure_mesh()
        .x_desc("time per shading evaluation (ns, log)")
        .y_desc("mean CIEDE2000 vs 1 nm exact (log)")
        .label_style(font(15))
        .axis_desc_style(font(17))
        .x_label_formatter(&|v| format_tick(*v))
        .y_label_formatter(&|v| format_tick(*v))
        .draw()?;
    chart.draw_series(
        points
            .iter()
            .map(|p| Circle::new((p.ns_per_eval, y_of(p)), 5, family_color(p.family).filled())),
    )?;
    let (label_px, char_px) = (13u32, 8);
    // Inside the axes, clear of the tick labels.
    let (area_x, area_y) = chart.plotting_area().get_pixel_range();
    let mut placed: Vec<Rect> = points
        .iter()
        .map(|p| {
            let (px, py) = chart.backend_coord(&(p.ns_per_eval, y_of(p)));
            (px - 6, py - 6, 12, 12)
        })
        .collect();
    for p in points {
        let point = chart.backend_coord(&(p.ns_per_eval, y_of(p)));
        let w = char_px * p.label.chars().count() as i32;
        let h = label_px as i32 + 2;
        let (x, y) = place_label(point, (w, h), (&area_x, &area_y), &placed);
        placed.push((x, y, w, h));
        root.draw(&Text::new(
            p.label.clone(),
            (x, y),
            font(label_px).color(&family_color(p.family)),
        ))?;
    }
    draw_legend(&root, families, size.0 as i32 - legend_width + 30)?;
    root.present()?;
    Ok(())
}

/// A box in pixels: left, top, width, height.
type Rect = (i32, i32, i32, i32);

/// Where a label of size (w, h) for the point at `(px, py)` goes (its
/// top-left corner): the first of a few positions around the point whose
/// box overlaps nothing in `placed` (points and labels) and stays inside
/// `area`, else the first position.
fn place_label(
    (px, py): (i32, i32),
    (w, h): (i32, i32),
    (area_x, area_y): (&Range<i32>, &Range<i32>),
    placed: &[Rect],
) -> (i32, i32) {
    let candidates = [
        (8, -h / 2),
        (8, -h - 2),
        (8, 4),
        (-w - 8, -h / 2),
        (-w - 8, -h - 2),
        (-w - 8, 4),
        (8, -2 * h - 4),
        (8, h + 6),
        (-w - 8, -2 * h - 4),
        (-w - 8, h + 6),
        (-w / 2, -h - 8),
        (-w / 2, 8),
        (-w / 2, -2 * h - 8),
        (-w / 2, h + 10),
    ];
    let inside = |x: i32, y: i32| {
        x >= area_x.start && y >= area_y.start && x + w <= area_x.end && y + h <= area_y.end
    };
    let free = |x: i32, y: i32| {
        placed
            .iter()
            .all(|&(ax, ay, aw, ah)| x + w <= ax || ax + aw <= x || y + h <= ay || ay + ah <= y)
    };
    let (dx, dy) = candidates
        .iter()
        .copied()
        .find(|&(dx, dy)| inside(px + dx, py + dy) && free(px + dx, py + dy))
        .unwrap_or(candidates[0]);
    (px + dx, py + dy)
}

/// One entry per family, in its colour, in a column at pixel `x`.
fn draw_legend(
    root: &DrawingArea<BitMapBackend<'_>, Shift>,
    families: &[&str],
    x: i32,
) -> std::result::Result<(), Box<dyn std::error::Error>> {
    for (i, name) in families.iter().enumerate() {
        let color = family_color(i);
        let y = 80 + 24 * i as i32;
        root.draw(&Circle::new((x, y), 5, color.filled()))?;
        root.draw(&Text::new(
            name.to_string(),
            (x + 12, y - 8),
            (FONT_NAME, 15).into_font().color(&color),
        ))?;
    }
    Ok(())
}

fn family_color(family: usize) -> RGBColor {
    FAMILY_COLORS[family % FAMILY_COLORS.len()]
}

/// Tick labels in plain decimal, short: 0.001, 0.5, 20, 3000, 1e+06.
fn format_tick(v: f64) -> String {
    if !(1e-4..1e6).contains(&v) {
        format!("{v:.0e}")
    } else if v >= 1.0 {
        format!("{v:.0}")
    } else {
        let digits = (-v.log10()).ceil() as usize;
        format!("{v:.digits$}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_a_png_with_labels() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.png");
        let points = vec![
            PlotPoint {
                label: "exact (at floor)".into(),
                family: 0,
                ns_per_eval: 20_000.0,
                mean_de2000: 0.0,
            },
            PlotPoint {
                label: "LUT 64x32".into(),
                family: 1,
                ns_per_eval: 12.0,
                mean_de2000: 0.8,
            },
        ];
        speed_vs_error_png(&path, &points, &["direct", "LUT"], 1e-3, "test").unwrap();
        let img = image::open(&path).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (1200, 760));
        // Something other than white was drawn: axes, points, text.
        let ink = img.pixels().filter(|p| p.0 != [255, 255, 255]).count();
        assert!(ink > 5_000, "{ink}");
        assert!(speed_vs_error_png(&path, &[], &[], 1e-3, "x").is_err());
    }

    #[test]
    fn ticks() {
        assert_eq!(format_tick(20.0), "20");
        assert_eq!(format_tick(0.5), "0.5");
        assert_eq!(format_tick(0.001), "0.001");
    }
}
