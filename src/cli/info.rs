//! `irid info LUT.exr`: the table's header in human form.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use irid::lut::rough::{is_rough_table, RoughHeader, RoughLut};
use irid::lut::{ColorInfo, Header, Lut};
use irid::stats::RoughFigures;

#[derive(clap::Args)]
pub struct Args {
    /// A table written by `irid bake`.
    pub lut: PathBuf,
}

pub fn run(args: Args) -> Result<ExitCode> {
    if is_rough_table(&args.lut) {
        return run_rough(&args);
    }
    let lut = Lut::load(&args.lut)?;
    let h = lut.header();
    let mut out = String::new();
    super::say!(out, "{}", args.lut.display());
    super::say!(
        out,
        "  {} v{}, {} table, {} samples, written by {}",
        h.format,
        h.version,
        h.kind,
        h.precision,
        h.tool
    );
    super::say!(out, "  cache key {}", h.cache_key);
    say_axes(&mut out, h);
    super::say!(out, "channels:");
    for c in &h.channels {
        super::say!(out, "  {:<16} {}", c.name, c.meaning);
    }
    say_stack(&mut out, h);
    say_colour(&mut out, &h.color);
    print_with_error(&mut out, h);
    Ok(ExitCode::SUCCESS)
}

/// The colour integration's line, smooth and rough tables alike.
fn say_colour(out: &mut String, c: &ColorInfo) {
    super::say!(
        out,
        "colour: {}, {}, {}, sampling {}",
        c.space,
        c.illuminant,
        c.observer,
        c.sampling
    );
}

fn say_axes(out: &mut String, h: &Header) {
    if let Some(t) = &h.atlas {
        say_atlas(out, h, t);
        return;
    }
    super::say!(
        out,
        "axes (x = {}, y = {}{}):",
        h.x_axis,
        h.y_axis,
        match &h.y_blocks {
            Some(b) => format!(", y in blocks of {b}"),
            None => String::new(),
        }
    );
    for a in &h.axes {
        let n = &a.nodes;
        let unit = if a.unit == "1" {
            String::new()
        } else {
            format!(" {}", a.unit)
        };
        super::say!(
            out,
            "  {:<14} {:>6} nodes  {} .. {}{unit}  ({})",
            a.name,
            n.len(),
            n[0],
            n[n.len() - 1],
            spacing(n),
        );
    }
}

/// An atlas table's domain and charts.
fn say_atlas(out: &mut String, h: &Header, t: &irid::lut::TableAtlas) {
    let a = &t.atlas;
    let (c0, c1) = {
        let n = &h.axes[1].nodes;
        (n[0], n[n.len() - 1])
    };
    super::say!(
        out,
        "atlas: {}×{} texels{}, thickness {} .. {} nm, cos θ {c0} .. {c1}{}{}",
        a.width,
        a.height,
        match h.axes.get(2) {
            Some(w) => format!(" per wavelength, {} wavelength nodes", w.nodes.len()),
            None => String::new(),
        },
        a.thickness_nm.0,
        a.thickness_nm.1,
        match (t.aliased_below_cos > 0.0, t.critical_band_cos) {
            (false, None) => String::new(),
            (true, None) => format!(" (fringes aliased below cos θ {:.6})", t.aliased_below_cos),
            (aliased, Some([a, b])) => format!(
                " ({}critical band cos θ {a:.6} .. {b:.6}, target not sought)",
                if aliased {
                    format!("fringes aliased below cos θ {:.6}; ", t.aliased_below_cos)
                } else {
                    String::new()
                }
            ),
        },
        match t.lossless_white {
            Some(w) => format!(
                "; lossless: T = ({:.6}, {:.6}, {:.6}) − R",
                w[0], w[1], w[2]
            ),
            None => String::new(),
        }
    );
    for c in &a.charts {
        let what = match c.coords {
            irid::atlas::Coords::Band { p, c } => format!(
                "band cos θ {:.6} .. {:.6}, optical thickness {:.2} .. {:.2} nm{}",
                c.lo,
                c.hi,
                p.lo_nm,
                p.hi_nm,
                if p.p0_nm > 0.0 {
                    format!(" (log, p0 {} nm)", p.p0_nm)
                } else {
                    String::new()
                }
            ),
            irid::atlas::Coords::Corner { scale_nm, radius } => {
                format!("grazing corner, scale {scale_nm:.2} nm, radius {radius}")
            }
        };
        super::say!(
            out,
            "  {}×{} at ({}, {}): {what}",
            c.rect.width,
            c.rect.height,
            c.rect.x,
            c.rect.y
        );
    }
}

/// "uniform step …", "non-uniform, steps … to …" or "single node".
fn spacing(nodes: &[f64]) -> String {
    let steps: Vec<f64> = nodes.windows(2).map(|w| w[1] - w[0]).collect();
    match (
        steps.iter().cloned().reduce(f64::min),
        steps.iter().cloned().reduce(f64::max),
    ) {
        (Some(lo), Some(hi)) if hi - lo <= 1e-9 * hi.abs().max(1.0) => {
            format!("uniform step {lo:.6}")
        }
        (Some(lo), Some(hi)) => format!("non-uniform, steps {lo:.3e} to {hi:.3e}"),
        _ => "single node".into(),
    }
}

fn say_stack(out: &mut String, h: &Header) {
    say_stack_of(out, &h.stack, h.layer);
}

/// The stack's media and layers, `layer` marked as the thickness axis.
fn say_stack_of(out: &mut String, stack: &irid::optics::Stack, layer: usize) {
    super::say!(out, "stack:");
    super::say!(out, "  ambient    {}", stack.ambient.name);
    for (i, l) in stack.layers.iter().enumerate() {
        let varying = if i + 1 == layer {
            "   <- thickness axis"
        } else {
            ""
        };
        let incoherent = if l.coherent { "" } else { " (incoherent)" };
        super::say!(
            out,
            "  layer {:<4} {} {} nm{incoherent}{varying}",
            i + 1,
            l.material.name,
            l.thickness_nm
        );
    }
    super::say!(out, "  substrate  {}", stack.substrate.name);
}

/// Prints `out` followed by the error section. The validation statistics
/// print themselves, so `out` is flushed before them.
fn print_with_error(out: &mut String, h: &Header) {
    super::say!(out, "error:");
    if let Some(e) = h.error.target_max_abs {
        super::say!(out, "  target (--max-error)  {e:e}");
    }
    match &h.error.bake_check {
        Some(check) => super::say!(
            out,
            "  bake check            max abs {:.3e} over {} points ({})",
            check.max_abs_all,
            check.points,
            check.metric
        ),
        None => super::say!(
            out,
            "  bake check            not made (baked with --no-check)"
        ),
    }
    if let Some(v) = &h.error.validation {
        super::say!(
            out,
            "  validation            {} against the solver (relative above 1):",
            crate::cli::validate::points_and_seed(v)
        );
        super::print_escaped(out);
        out.clear();
        crate::cli::validate::print_stats(v);
    } else {
        super::say!(
            out,
            "  validation            not recorded (run `irid validate`)"
        );
        super::print_escaped(out);
    }
}

/// `irid info` on a rough table (`irid bake --rough`).
fn run_rough(args: &Args) -> Result<ExitCode> {
    let rough = RoughLut::load(&args.lut)?;
    let h = rough.header();
    let mut out = String::new();
    super::say!(out, "{}", args.lut.display());
    super::say!(
        out,
        "  {} v{}, rough table (F_eff, f32 R G B), written by {}",
        h.format,
        h.version,
        h.tool
    );
    super::say!(
        out,
        "slices: {} ({}), each {}x{} texels, {} front chart(s), thickness {} .. {} nm",
        h.slices,
        h.slice_rule,
        h.atlas.width,
        h.atlas.height,
        h.atlas.charts.len(),
        h.atlas.thickness_nm.0,
        h.atlas.thickness_nm.1
    );
    say_stack_of(&mut out, &h.stack, h.layer);
    say_colour(&mut out, &h.color);
    super::print_escaped(&out);
    print_rough_error(h);
    Ok(ExitCode::SUCCESS)
}

/// A rough table's error section: the target, the measured figures above
/// and below the grazing strip, the blend's predicted error.
pub fn print_rough_error(h: &RoughHeader) {
    let e = &h.error;
    let mut out = String::new();
    super::say!(
        out,
        "error: target {:.1e} (max abs per channel against irid's rough reflectance, cos θ ≥ {}); slice blend predicted {:.2e}",
        e.target_max_abs,
        e.grazing_cos,
        e.blend_error
    );
    say_slice_error(&mut out, &format!("cos θ ≥ {}", e.grazing_cos), &e.measured);
    say_slice_error(
        &mut out,
        &format!("cos θ < {} (not sought)", e.grazing_cos),
        &e.grazing,
    );
    super::print_escaped(&out);
}

/// One line of measured figures.
pub fn say_slice_error(out: &mut String, name: &str, e: &RoughFigures) {
    if e.points == 0 {
        super::say!(out, "  {name}: no points");
        return;
    }
    let [t, c, r] = e.worst_point;
    super::say!(
        out,
        "  {name}: {} points, max abs {:.3e} {:.3e} {:.3e} (R G B), p99 {:.3e}, mean {:.3e}; ΔE00 max {:.3} mean {:.4}; worst at {t:.1} nm, cos θ {c:.4}, roughness {r:.3}",
        e.points,
        e.max_abs[0],
        e.max_abs[1],
        e.max_abs[2],
        e.p99_abs.iter().fold(0.0f64, |a, &b| a.max(b)),
        e.mean_abs.iter().fold(0.0f64, |a, &b| a.max(b)),
        e.max_delta_e00,
        e.mean_delta_e00
    );
}
