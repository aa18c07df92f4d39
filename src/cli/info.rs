//! `irid info LUT.exr`: the table's header in human form.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use irid::lut::{Header, Lut};

#[derive(clap::Args)]
pub struct Args {
    /// A table written by `irid bake`.
    pub lut: PathBuf,
}

pub fn run(args: Args) -> Result<ExitCode> {
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
    super::say!(
        out,
        "colour: {}, {}, {}, sampling {}",
        h.color.space,
        h.color.illuminant,
        h.color.observer,
        h.color.sampling
    );
    print_with_error(&mut out, h);
    Ok(ExitCode::SUCCESS)
}

fn say_axes(out: &mut String, h: &Header) {
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
    super::say!(out, "stack:");
    super::say!(out, "  ambient    {}", h.stack.ambient.name);
    for (i, l) in h.stack.layers.iter().enumerate() {
        let varying = if i + 1 == h.layer {
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
    super::say!(out, "  substrate  {}", h.stack.substrate.name);
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
            "  validation            {} random points (seed {}) against the solver:",
            v.points,
            v.seed
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
