//! `irid color`: a stack's reflected and transmitted colour, per angle, in
//! linear sRGB with the chosen white (D65 by default), seen from the
//! ambient or (`--side substrate`) from the substrate; with `--roughness`,
//! its reflectance and transmittance pre-integrated over GGX lobes
//! (docs/rough.md).

use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{anyhow, Result};
use irid::color::{linear_to_srgb8, stack_colors, Sampling, SpectralIntegrator, White};
use irid::optics::Stack;
use irid::rough::{check_roughness, rough_colors_from, seen_from};
use irid::sweep::Side;

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
    /// GGX roughness in [0, 1] (α = roughness²): print F_eff and T_eff, the
    /// film's reflectance and transmittance pre-integrated over the
    /// microfacet reflection and refraction lobes, per view angle, and the
    /// white lobes' albedos, instead of the mirror's R and T (see
    /// docs/rough.md). 0 gives the mirror's exactly.
    #[arg(long)]
    pub roughness: Option<String>,
    /// The side the film is seen from: front (the view in the ambient) or
    /// substrate (the view in the substrate, which must not absorb; angles
    /// are then in the substrate).
    #[arg(long, default_value = "front")]
    pub side: String,
    /// One JSON array of {angle_deg, reflectance_rgb, transmittance_rgb,
    /// reflectance_xyz, transmittance_xyz} (linear sRGB; XYZ with Y = 1 for
    /// white); with --roughness, of {angle_deg, roughness, reflectance_rgb,
    /// reflectance_xyz, lobe_albedo, transmittance_rgb, transmittance_xyz,
    /// transmission_lobe_albedo} (single scattering: F_eff, T_eff, A_R, A_T)
    /// and {reflectance_ms_rgb, reflectance_ms_xyz, transmittance_ms_rgb,
    /// transmittance_ms_xyz} (F_eff and T_eff compensated for multiple
    /// scattering; the fluxes are A_R and A_T times them).
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<ExitCode> {
    let sampling: Sampling = parse_choice(&args.sampling)?;
    let white: White = parse_choice(&args.white)?;
    let angles_deg = parse_list("--angles", &args.angles)?;
    check_angles("--angles", &angles_deg)?;
    let roughness = args.roughness.as_deref().map(parse_roughness).transpose()?;
    let side = parse_side(&args.side)?;
    let stack = Stack::load(&args.stack)?;
    let integrator = SpectralIntegrator::with_white(sampling, white);
    check_grid(
        "--angles × --sampling wavelengths",
        &[angles_deg.len(), integrator.wavelengths_nm().len()],
    )?;
    let printer = Printer::new(&args, sampling, white);
    let in_file = |e: irid::Error| anyhow!("{}: {e}", args.stack.display());
    match roughness {
        Some(r) => {
            let colors =
                rough_colors_from(&stack, &integrator, &angles_deg, r, side).map_err(in_file)?;
            printer.rough(&colors, r)
        }
        None => {
            let (seen, _) = seen_from(&stack, 1, side, &integrator).map_err(in_file)?;
            let colors = stack_colors(&seen, &integrator, &angles_deg).map_err(in_file)?;
            printer.smooth(&colors)
        }
    }
}

/// `--side`: front or substrate.
fn parse_side(text: &str) -> Result<Side> {
    match text {
        "front" => Ok(Side::Front),
        "substrate" => Ok(Side::Back),
        _ => Err(anyhow!("--side '{text}': expected front or substrate")),
    }
}

/// `--roughness`: a number in [0, 1].
fn parse_roughness(text: &str) -> Result<f64> {
    let r: f64 = text
        .trim()
        .parse()
        .map_err(|_| anyhow!("--roughness '{text}': not a number"))?;
    check_roughness("--roughness", r)?;
    Ok(r)
}

/// Writes colours as JSON or as a table with swatches.
struct Printer<'a> {
    args: &'a Args,
    sampling: Sampling,
    white: White,
    /// A block of the colour itself when a terminal is there to show it.
    swatches: bool,
}

impl Printer<'_> {
    fn new(args: &Args, sampling: Sampling, white: White) -> Printer<'_> {
        Printer {
            args,
            sampling,
            white,
            swatches: std::io::stdout().is_terminal(),
        }
    }

    fn swatch(&self, rgb: [f64; 3]) -> String {
        let [r, g, b] = linear_to_srgb8(rgb);
        let hex = format!("#{r:02x}{g:02x}{b:02x}");
        if self.swatches {
            format!("\x1b[48;2;{r};{g};{b}m    \x1b[0m {hex}")
        } else {
            hex
        }
    }

    /// The first line: stack, side, white, observer, sampling, and `what`.
    fn heading(&self, out: &mut impl Write, what: &str) -> Result<()> {
        writeln!(
            out,
            "{}{}: {}, CIE 1931 2°, sampling {}{what}; linear sRGB with the sRGB-encoded hex",
            self.args.stack.display(),
            if self.args.side == "substrate" {
                " seen from its substrate"
            } else {
                ""
            },
            match self.white {
                White::D65 => "D65",
                White::E => "white E (flat spectrum = 1)",
            },
            self.sampling,
        )?;
        Ok(())
    }

    fn smooth(&self, colors: &[irid::color::FilmColor]) -> Result<ExitCode> {
        let mut out = std::io::stdout().lock();
        if self.args.json {
            serde_json::to_writer_pretty(&mut out, colors)?;
            writeln!(out)?;
            return Ok(ExitCode::SUCCESS);
        }
        self.heading(&mut out, "")?;
        // Visible width of a swatch, a space and a padded triple.
        let width = if self.swatches { 40 } else { 35 };
        let rows = colors
            .iter()
            .map(|c| (c.angle_deg, c.reflectance_rgb, c.transmittance_rgb));
        self.reflectance_and_transmittance(&mut out, width, rows)?;
        Ok(ExitCode::SUCCESS)
    }

    /// A table of angle, reflectance and transmittance, each colour with
    /// its swatch; `width` is the reflectance column's visible width.
    fn reflectance_and_transmittance(
        &self,
        out: &mut impl Write,
        width: usize,
        rows: impl Iterator<Item = (f64, [f64; 3], [f64; 3])>,
    ) -> Result<()> {
        writeln!(
            out,
            "{:>7}  {:<width$}  transmittance",
            "angle", "reflectance"
        )?;
        for (angle_deg, reflectance, transmittance) in rows {
            writeln!(
                out,
                "{:>6.2}°  {} {:<27}  {} {}",
                angle_deg,
                self.swatch(reflectance),
                triple(reflectance),
                self.swatch(transmittance),
                triple(transmittance),
            )?;
        }
        Ok(())
    }

    fn rough(&self, colors: &[irid::rough::RoughColor], roughness: f64) -> Result<ExitCode> {
        let mut out = std::io::stdout().lock();
        if self.args.json {
            serde_json::to_writer_pretty(&mut out, colors)?;
            writeln!(out)?;
            return Ok(ExitCode::SUCCESS);
        }
        self.heading(
            &mut out,
            &format!(
                ", GGX roughness {roughness} (α = {:.4}): reflectance and transmittance pre-integrated over the lobes (single scattering), each lobe's white albedo beside",
                roughness * roughness
            ),
        )?;
        let width = if self.swatches { 40 } else { 35 };
        writeln!(
            out,
            "{:>7}  {:<width$}  lobe albedo  {:<width$}  lobe albedo",
            "angle", "reflectance", "transmittance"
        )?;
        for c in colors {
            writeln!(
                out,
                "{:>6.2}°  {} {:<27}  {:<11.4}  {} {:<27}  {:.4}",
                c.angle_deg,
                self.swatch(c.reflectance_rgb),
                triple(c.reflectance_rgb),
                c.lobe_albedo,
                self.swatch(c.transmittance_rgb),
                triple(c.transmittance_rgb),
                c.transmission_lobe_albedo,
            )?;
        }
        writeln!(
            out,
            "\ncompensated for multiple scattering (times the same white lobes' albedos):"
        )?;
        let rows = colors
            .iter()
            .map(|c| (c.angle_deg, c.reflectance_ms_rgb, c.transmittance_ms_rgb));
        self.reflectance_and_transmittance(&mut out, width, rows)?;
        Ok(ExitCode::SUCCESS)
    }
}

fn triple(v: [f64; 3]) -> String {
    format!("({:.4}, {:.4}, {:.4})", v[0], v[1], v[2])
}
