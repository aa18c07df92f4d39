//! `irid info LUT.exr`: the table's header in human form.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use irid::lut::Lut;

#[derive(clap::Args)]
pub struct Args {
    /// A table written by `irid bake`.
    pub lut: PathBuf,
}

pub fn run(args: Args) -> Result<ExitCode> {
    let lut = Lut::load(&args.lut)?;
    let h = lut.header();
    println!("{}", args.lut.display());
    println!(
        "  {} v{}, {} table, {} samples, written by {}",
        h.format, h.version, h.kind, h.precision, h.tool
    );
    println!("  cache key {}", h.cache_key);
    println!(
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
        let steps: Vec<f64> = n.windows(2).map(|w| w[1] - w[0]).collect();
        let spacing = match (
            steps.iter().cloned().reduce(f64::min),
            steps.iter().cloned().reduce(f64::max),
        ) {
            (Some(lo), Some(hi)) if hi - lo <= 1e-9 * hi.abs().max(1.0) => {
                format!("uniform step {lo:.6}")
            }
            (Some(lo), Some(hi)) => format!("non-uniform, steps {lo:.3e} to {hi:.3e}"),
            _ => "single node".into(),
        };
        let unit = if a.unit == "1" {
            String::new()
        } else {
            format!(" {}", a.unit)
        };
        println!(
            "  {:<14} {:>6} nodes  {} .. {}{unit}  ({spacing})",
            a.name,
            n.len(),
            n[0],
            n[n.len() - 1],
        );
    }
    println!("channels:");
    for c in &h.channels {
        println!("  {:<16} {}", c.name, c.meaning);
    }
    println!("stack:");
    println!("  ambient    {}", h.stack.ambient.name);
    for (i, l) in h.stack.layers.iter().enumerate() {
        let varying = if i + 1 == h.layer {
            "   <- thickness axis"
        } else {
            ""
        };
        println!(
            "  layer {:<4} {} {} nm{varying}",
            i + 1,
            l.material.name,
            l.thickness_nm
        );
    }
    println!("  substrate  {}", h.stack.substrate.name);
    println!(
        "colour: {}, {}, {}, sampling {}",
        h.color.space, h.color.illuminant, h.color.observer, h.color.sampling
    );
    println!("error:");
    if let Some(e) = h.error.target_max_abs {
        println!("  target (--max-error)  {e:e}");
    }
    match &h.error.bake_check {
        Some(check) => println!(
            "  bake check            max abs {:.3e} over {} points ({})",
            check.max_abs_all, check.points, check.metric
        ),
        None => println!("  bake check            not made (baked with --no-check)"),
    }
    if let Some(v) = &h.error.validation {
        println!(
            "  validation            {} random points (seed {}) against the solver:",
            v.points, v.seed
        );
        crate::cli::validate::print_stats(v);
    } else {
        println!("  validation            not recorded (run `irid validate`)");
    }
    Ok(ExitCode::SUCCESS)
}
