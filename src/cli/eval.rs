//! `irid eval`: R and T of one or more stacks over a wavelength × angle grid.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use serde::Serialize;

use irid::optics::{Response, Stack, StackGrid, WAVELENGTH_RANGE_NM};

use super::args::{check_angles, check_grid, parse_list};

#[derive(clap::Args)]
pub struct Args {
    /// Stack file(s) (TOML). With several, `--json` prints one array per
    /// stack, one per line, in order; the table prints one block per stack.
    #[arg(required = true)]
    pub stacks: Vec<PathBuf>,
    /// Vacuum wavelengths in nm: `a,b,c` or inclusive `start:end:step`.
    #[arg(long, default_value = "380:780:10", allow_hyphen_values = true)]
    pub wavelengths: String,
    /// Angles of incidence in the ambient, degrees in [0, 90): same forms.
    #[arg(long, default_value = "0,30,60", allow_hyphen_values = true)]
    pub angles: String,
    /// Print JSON (an array of objects) instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// One output row; the field names are the JSON keys.
#[derive(Serialize)]
struct Row {
    wavelength_nm: f64,
    angle_deg: f64,
    #[serde(rename = "Rs")]
    rs: f64,
    #[serde(rename = "Rp")]
    rp: f64,
    #[serde(rename = "Ts")]
    ts: f64,
    #[serde(rename = "Tp")]
    tp: f64,
    #[serde(rename = "R")]
    r: f64,
    #[serde(rename = "T")]
    t: f64,
}

pub fn run(args: Args) -> Result<ExitCode> {
    let wavelengths_nm = parse_list("--wavelengths", &args.wavelengths)?;
    let (lo, hi) = WAVELENGTH_RANGE_NM;
    if let Some(w) = wavelengths_nm.iter().find(|w| !(lo..=hi).contains(*w)) {
        anyhow::bail!("--wavelengths: {w} nm is outside {lo:e}–{hi:e} nm");
    }
    let angles_deg = parse_list("--angles", &args.angles)?;
    check_angles("--angles", &angles_deg)?;
    check_grid(
        "--wavelengths × --angles",
        &[wavelengths_nm.len(), angles_deg.len()],
    )?;
    let cos_theta0: Vec<f64> = angles_deg.iter().map(|a| a.to_radians().cos()).collect();

    // Everything is computed before anything is printed, so an error in
    // the last stack leaves no partial output behind.
    let mut blocks = Vec::with_capacity(args.stacks.len());
    let mut responses = vec![Response::default(); wavelengths_nm.len() * angles_deg.len()];
    for path in &args.stacks {
        let stack = Stack::load(path)?;
        let grid =
            StackGrid::new(&stack, &wavelengths_nm).with_context(|| path.display().to_string())?;
        grid.solve(&cos_theta0, &mut responses);
        grid.check_solved(&cos_theta0, &responses)
            .with_context(|| path.display().to_string())?;
        let rows: Vec<Row> = responses
            .iter()
            .enumerate()
            .map(|(i, r)| Row {
                wavelength_nm: wavelengths_nm[i / angles_deg.len()],
                angle_deg: angles_deg[i % angles_deg.len()],
                rs: r.rs,
                rp: r.rp,
                ts: r.ts,
                tp: r.tp,
                r: r.r(),
                t: r.t(),
            })
            .collect();
        blocks.push(rows);
    }

    let mut text = String::new();
    for (path, rows) in args.stacks.iter().zip(&blocks) {
        if args.json {
            text += &serde_json::to_string(rows)?;
            text.push('\n');
        } else {
            if args.stacks.len() > 1 {
                writeln!(text, "# {}", path.display())?;
            }
            table(&mut text, rows)?;
        }
    }
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|_| out.flush())
        .context("writing to stdout")?;
    Ok(ExitCode::SUCCESS)
}

fn table(text: &mut String, rows: &[Row]) -> std::fmt::Result {
    writeln!(
        text,
        "{:>13} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}",
        "wavelength_nm", "angle_deg", "Rs", "Rp", "Ts", "Tp", "R", "T"
    )?;
    for r in rows {
        writeln!(
            text,
            "{:>13.2} {:>9.3} {:>9.6} {:>9.6} {:>9.6} {:>9.6} {:>9.6} {:>9.6}",
            r.wavelength_nm, r.angle_deg, r.rs, r.rp, r.ts, r.tp, r.r, r.t
        )?;
    }
    Ok(())
}
