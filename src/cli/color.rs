//! `irid color`: a stack's reflected and transmitted colour, per angle, in
//! linear sRGB with the chosen white (D65 by default).

use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{anyhow, Result};
use irid::color::{linear_to_srgb8, stack_colors, Sampling, SpectralIntegrator, White};
use irid::optics::Stack;

use super::args::{check_angles, check_grid, parse_choice, parse_list};

#[derive(clap::Args)]
pub struct Args {
    /// Stack file (TOML).
    pub stack: PathBuf,
    /// Incidence angles in degrees, in [0, 90): `a,b,c` or `start:end:step`.
    #[arg(long, default_value = "0:80:10")]
    pub angles: String,
    /// Wavelength sampling: exact (1 nm, 360-830 nm), uniform:N (380-780 nm), rgb3.
    #[arg(long, default_value = "exact")]
    pub sampling: String,
    /// What (1, 1, 1) is: d65 (a perfect reflector under D65) or e (a flat
    /// spectrum, as Blender Cycles and glTF viewers); see docs/color.md.
    #[arg(long, default_value = "d65")]
    pub white: String,
    /// One JSON array of {angle_deg, reflectance_rgb, transmittance_rgb,
    /// reflectance_xyz, transmittance_xyz} (linear sRGB; XYZ with Y = 1 for white).
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<ExitCode> {
    let sampling: Sampling = parse_choice(&args.sampling)?;
    let white: White = parse_choice(&args.white)?;
    let angles_deg = parse_list("--angles", &args.angles)?;
    check_angles("--angles", &angles_deg)?;
    let stack = Stack::load(&args.stack)?;
    let integrator = SpectralIntegrator::with_white(sampling, white);
    check_grid(
        "--angles × --sampling wavelengths",
        &[angles_deg.len(), integrator.wavelengths_nm().len()],
    )?;
    let colors = stack_colors(&stack, &integrator, &angles_deg)
        .map_err(|e| anyhow!("{}: {e}", args.stack.display()))?;

    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    if args.json {
        serde_json::to_writer_pretty(&mut out, &colors)?;
        writeln!(out)?;
        return Ok(ExitCode::SUCCESS);
    }
    // A block of the colour itself when a terminal is there to show it.
    let swatches = stdout.is_terminal();
    let swatch = |rgb: [f64; 3]| {
        let [r, g, b] = linear_to_srgb8(rgb);
        let hex = format!("#{r:02x}{g:02x}{b:02x}");
        if swatches {
            format!("\x1b[48;2;{r};{g};{b}m    \x1b[0m {hex}")
        } else {
            hex
        }
    };
    let triple = |v: [f64; 3]| format!("({:.4}, {:.4}, {:.4})", v[0], v[1], v[2]);
    writeln!(
        out,
        "{}: {}, CIE 1931 2°, sampling {sampling}; linear sRGB with the sRGB-encoded hex",
        args.stack.display(),
        match white {
            White::D65 => "D65",
            White::E => "white E (flat spectrum = 1)",
        }
    )?;
    // Visible width of a swatch, a space and a padded triple.
    let width = if swatches { 40 } else { 35 };
    writeln!(
        out,
        "{:>7}  {:<width$}  transmittance",
        "angle", "reflectance"
    )?;
    for c in &colors {
        writeln!(
            out,
            "{:>6.2}°  {} {:<27}  {} {}",
            c.angle_deg,
            swatch(c.reflectance_rgb),
            triple(c.reflectance_rgb),
            swatch(c.transmittance_rgb),
            triple(c.transmittance_rgb),
        )?;
    }
    Ok(ExitCode::SUCCESS)
}
