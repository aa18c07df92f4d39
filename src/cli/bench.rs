//! `irid bench`: speed against error, and the grid workload the Python peers
//! (`tools/bench_peers.py`) are timed against.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use irid::bench::{grid, report, stacks};

use super::args::{check_angles, parse_list};

#[derive(clap::Args)]
pub struct Args {
    /// Grid mode: evaluate one of the fixed stacks over a wavelength × angle
    /// (× thickness) grid and report the wall time.
    #[arg(long, value_name = "STACK")]
    pub grid: String,
    /// Wavelengths in nm: a,b,c or start:end:step.
    #[arg(long, default_value = "380:780:1")]
    pub wavelengths: String,
    /// Incidence angles in degrees: a,b,c or start:end:step.
    #[arg(long, default_value = "0:89:1")]
    pub angles: String,
    /// Thicknesses in nm of the stack's varying layer (default: its own thickness).
    #[arg(long)]
    pub thicknesses: Option<String>,
    /// Worker threads.
    #[arg(long, default_value_t = 2)]
    pub threads: usize,
    /// Repetitions; the fastest is reported.
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
    /// Write R then T as little-endian f64 arrays, [thickness][angle][wavelength],
    /// to this file instead of printing them in the JSON.
    #[arg(long, value_name = "PATH")]
    pub raw: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<ExitCode> {
    run_grid(&args)?;
    Ok(ExitCode::SUCCESS)
}

fn run_grid(args: &Args) -> Result<()> {
    let bench = stacks::find(&args.grid)?.with_context(|| {
        format!(
            "--grid '{}': unknown stack (known: {})",
            args.grid,
            stacks::names().join(", ")
        )
    })?;
    let wavelengths_nm = parse_list("--wavelengths", &args.wavelengths)?;
    let angles_deg = parse_list("--angles", &args.angles)?;
    check_angles("--angles", &angles_deg)?;
    let thicknesses_nm = match &args.thicknesses {
        Some(spec) => {
            let t = parse_list("--thicknesses", spec)?;
            if let Some(bad) = t.iter().find(|t| **t < 0.0) {
                anyhow::bail!("--thicknesses: {bad} is negative");
            }
            Some(t)
        }
        None => None,
    };
    if args.threads == 0 {
        anyhow::bail!("--threads must be at least 1");
    }
    let g = grid::Grid {
        wavelengths_nm,
        angles_deg,
        thicknesses_nm,
    };
    let out = grid::evaluate(
        &bench.stack,
        bench.varying_layer,
        &g,
        args.threads,
        args.repeat,
    )?;
    let (indices_re, indices_im): (Vec<Vec<f64>>, Vec<Vec<f64>>) = out
        .indices
        .chunks(out.media)
        .map(|c| {
            (
                c.iter().map(|z| z.re).collect(),
                c.iter().map(|z| z.im).collect(),
            )
        })
        .unzip();
    let mut doc = serde_json::json!({
        "stack": bench.name,
        "description": bench.description,
        "layer_thicknesses_nm": bench.stack.thicknesses_nm(),
        "varying_layer": bench.varying_layer,
        "wavelengths_nm": g.wavelengths_nm,
        "angles_deg": g.angles_deg,
        "thicknesses_nm": g.thicknesses_nm,
        "indices_re": indices_re,
        "indices_im": indices_im,
        "threads": args.threads,
        "points": g.points(),
        "seconds": out.seconds,
    });
    match &args.raw {
        Some(path) => {
            write_raw(path, &out.r, &out.t)?;
            doc["raw"] = serde_json::json!(path);
        }
        None => {
            doc["r"] = serde_json::json!(out.r);
            doc["t"] = serde_json::json!(out.t);
        }
    }
    let mut stdout = std::io::stdout().lock();
    serde_json::to_writer(&mut stdout, &doc)?;
    writeln!(stdout)?;
    Ok(())
}

/// R then T as little-endian f64, written atomically.
fn write_raw(path: &Path, r: &[f64], t: &[f64]) -> Result<()> {
    let mut bytes = Vec::with_capacity(16 * r.len());
    for v in r.iter().chain(t) {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    Ok(report::write_atomic(path, &bytes)?)
}
