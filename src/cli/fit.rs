//! `irid fit`: layer thicknesses from a measured spectrum (`--spectrum`) or
//! from colours seen at given angles (`--color`); prints each thickness ± σ,
//! χ² and the residual, and writes the fitted stack (`-o`).

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{anyhow, bail, Context, Result};
use irid::atomic::OutputSet;
use irid::color::{Sampling, SpectralIntegrator, White};
use irid::fit::{
    check_target, fit_color, fit_spectrum, read_spectrum_csv, with_thicknesses, ColorFit,
    ColorTarget, SpectrumFit, Vary,
};
use irid::optics::Stack;

use super::args::{parse_choice, parse_range};

#[derive(clap::Args)]
pub struct Args {
    /// Stack file (TOML): the materials, and the start of the varied layers.
    pub stack: PathBuf,
    /// Measured spectrum (CSV): columns wavelength_nm, angle_deg, R and/or
    /// T, optional sigma, named in a header line.
    #[arg(long, conflicts_with = "color")]
    pub spectrum: Option<PathBuf>,
    /// A target colour R,G,B@ANGLE: linear sRGB of the reflectance under
    /// --white, seen at ANGLE degrees; repeat the flag for several angles.
    #[arg(long, action = clap::ArgAction::Append)]
    pub color: Vec<String>,
    /// The layers to fit, counted from 1 at the ambient side: `1,2`.
    #[arg(long, required = true)]
    pub vary: String,
    /// Each varied layer's bounds in nm, LO:HI, comma-separated in the
    /// order of --vary [default: ±50 % around its thickness in the stack].
    #[arg(long)]
    pub bounds: Option<String>,
    /// With --color: what (1, 1, 1) is, d65 or e (see docs/color.md).
    #[arg(long, default_value = "d65")]
    pub white: String,
    /// Write the fitted stack here (the stack file with the new thicknesses).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Print the fit as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<ExitCode> {
    let layers = parse_layers(&args.vary)?;
    let bounds = args.bounds.as_deref().map(parse_bounds).transpose()?;
    let white: White = parse_choice(&args.white)?;
    let targets = args
        .color
        .iter()
        .map(|c| parse_color(c))
        .collect::<Result<Vec<_>>>()?;
    let integrator = SpectralIntegrator::with_white(Sampling::Exact, white);
    for (text, target) in args.color.iter().zip(&targets) {
        check_target(&integrator, target, &format!("--color '{text}'"))?;
    }
    if args.spectrum.is_none() && targets.is_empty() {
        bail!("--spectrum or --color: give a measured spectrum or target colours");
    }
    let text = irid::limits::read_text(&args.stack)?;
    let base_dir = args.stack.parent().unwrap_or(Path::new(""));
    let origin = args.stack.display().to_string();
    let stack = Stack::from_toml_str(&text, base_dir, &origin)?;
    let vary = Vary::new(&stack, &layers, bounds.as_deref(), "--vary", "--bounds")?;
    // The output's path is checked before the work, so that a bad one
    // fails at once and nothing is written on any error.
    let mut set = OutputSet::new();
    let output = args.output.as_ref().map(|o| set.file(o));
    let mut prepared = set.prepare()?;
    let (thicknesses, report) = match &args.spectrum {
        Some(path) => {
            let measured = read_spectrum_csv(path)?;
            let name = path.display().to_string();
            measured.check(&name, layers.len())?;
            let fit = fit_spectrum(&stack, &vary, &measured).with_context(|| name.clone())?;
            (
                fit.thickness_nm.clone(),
                spectrum_report(&fit, &name, args.json)?,
            )
        }
        None => {
            let fit = fit_color(&stack, &vary, &targets, white, None)?;
            (fit.thickness_nm.clone(), color_report(&fit, args.json)?)
        }
    };
    if let (Some(handle), Some(path)) = (output, &args.output) {
        let set: Vec<(usize, f64)> = layers.iter().copied().zip(thicknesses).collect();
        let to_dir = path.parent().unwrap_or(Path::new(""));
        let fitted = with_thicknesses(&text, &origin, &set, base_dir, to_dir)?;
        prepared.write(handle, |tmp| {
            std::fs::write(tmp, fitted.as_bytes()).map_err(|e| irid::Error::io(path, e))
        })?;
        prepared.commit()?;
    }
    let mut out = std::io::stdout().lock();
    out.write_all(report.as_bytes())
        .and_then(|_| out.flush())
        .context("writing to stdout")?;
    Ok(ExitCode::SUCCESS)
}

/// `--vary 1,2`: layer numbers.
fn parse_layers(text: &str) -> Result<Vec<usize>> {
    text.split(',')
        .map(|s| {
            s.trim()
                .parse::<usize>()
                .map_err(|_| anyhow!("--vary '{text}': '{}' is not a layer number", s.trim()))
        })
        .collect()
}

/// `--bounds 100:300,50:150`.
fn parse_bounds(text: &str) -> Result<Vec<(f64, f64)>> {
    text.split(',')
        .map(|r| parse_range("--bounds", r))
        .collect()
}

/// `--color R,G,B@ANGLE`.
fn parse_color(text: &str) -> Result<ColorTarget> {
    let bad = |why: &str| anyhow!("--color '{text}': {why}");
    let (rgb, angle) = text
        .split_once('@')
        .ok_or_else(|| bad("expected R,G,B@ANGLE"))?;
    let number = |s: &str| -> Result<f64> {
        let v: f64 = s
            .trim()
            .parse()
            .map_err(|_| bad(&format!("'{}' is not a number", s.trim())))?;
        if !v.is_finite() {
            return Err(bad(&format!("'{}' is not finite", s.trim())));
        }
        Ok(v)
    };
    let channels: Vec<f64> = rgb.split(',').map(number).collect::<Result<_>>()?;
    let [r, g, b] = channels[..] else {
        return Err(bad("expected three channels R,G,B"));
    };
    let angle_deg = number(angle)?;
    if !(0.0..90.0).contains(&angle_deg) {
        return Err(bad(&format!(
            "angle {angle_deg} is outside [0, 90) degrees"
        )));
    }
    Ok(ColorTarget {
        angle_deg,
        rgb: [r, g, b],
    })
}

fn spectrum_report(fit: &SpectrumFit, name: &str, json: bool) -> Result<String> {
    if json {
        return Ok(serde_json::to_string_pretty(fit)? + "\n");
    }
    let mut text = String::new();
    writeln!(text, "fitted to {name}:")?;
    for ((layer, d), s) in fit.layers.iter().zip(&fit.thickness_nm).zip(&fit.sigma_nm) {
        writeln!(text, "  layer {layer}: {d:.3} ± {s:.3} nm")?;
    }
    writeln!(
        text,
        "χ² = {} over {} degrees of freedom (reduced {})",
        number(fit.chi2),
        fit.degrees_of_freedom,
        number(fit.chi2 / fit.degrees_of_freedom.max(1) as f64)
    )?;
    writeln!(
        text,
        "residual: rms of model − measured {:.3e}",
        fit.rms_residual
    )?;
    if fit.alternatives.is_empty() {
        writeln!(
            text,
            "unique: no other minimum within Δχ² {} of the best",
            number(fit.threshold)
        )?;
    }
    for alt in &fit.alternatives {
        let at: Vec<String> = alt.thickness_nm.iter().map(|d| format!("{d:.3}")).collect();
        writeln!(
            text,
            "ambiguous: thicknesses {} nm fit as well (Δχ² {} ≤ {})",
            at.join(", "),
            number(alt.chi2 - fit.chi2),
            number(fit.threshold)
        )?;
    }
    Ok(text)
}

/// Four decimals, or four significant digits in exponent form below 0.01.
fn number(x: f64) -> String {
    if x != 0.0 && x.abs() < 1e-2 {
        format!("{x:.3e}")
    } else {
        format!("{x:.4}")
    }
}

fn color_report(fit: &ColorFit, json: bool) -> Result<String> {
    if json {
        return Ok(serde_json::to_string_pretty(fit)? + "\n");
    }
    let mut text = String::new();
    for (layer, d) in fit.layers.iter().zip(&fit.thickness_nm) {
        writeln!(text, "layer {layer}: {d:.3} nm")?;
    }
    for ((angle, de), rgb) in fit.angle_deg.iter().zip(&fit.delta_e2000).zip(&fit.rgb) {
        writeln!(
            text,
            "{angle:>6.2}°  ΔE00 {de:.3}  fitted ({:.4}, {:.4}, {:.4})",
            rgb[0], rgb[1], rgb[2]
        )?;
    }
    let tolerance = fit.tolerance_de2000;
    if fit.alternatives.is_empty() {
        writeln!(
            text,
            "unique: no other thickness matches within ΔE00 {tolerance} of the best"
        )?;
    }
    for alt in &fit.alternatives {
        let at: Vec<String> = alt.thickness_nm.iter().map(|d| format!("{d:.3}")).collect();
        let worst = alt.delta_e2000.iter().copied().fold(0.0, f64::max);
        writeln!(
            text,
            "ambiguous: thicknesses {} nm match as well (largest ΔE00 {worst:.3}, within {tolerance} of the best): add angles to tell them apart",
            at.join(", ")
        )?;
    }
    Ok(text)
}
